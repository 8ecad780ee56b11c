"""The grading process: imports ONE student module and calls its function on every case.

    python runner.py RESULTS < job.json

The grader (`shadowvol.course.grader`) starts one such process per task, with a time limit,
so that an endless loop, a crash or an `os._exit` costs that task only.  The job on stdin is
JSON: {"workspace", "module", "function", "args": [[...], ...]}.  The answers are written to
the file RESULTS as JSON, one entry per case: {"value": ...} or {"error": "what it raised"}.
This process never sees the expected answers.  It imports nothing of this project (it runs
as a script, this folder taken off sys.path), so a student's module named like one of ours is
still the student's; and it lets no student module import it either (`Withheld`): the answers
are the project's own functions, which a student's could otherwise simply call.
"""

from __future__ import annotations

import importlib.util
import json
import os
import sys
import traceback


WITHHELD = ("shadowvol", "raytrace")


class Withheld:
    """A meta-path finder refusing this project's packages to the student's code."""

    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in WITHHELD:
            raise ImportError(f"{name} is not available while grading: the grader checks "
                              f"your code against it", name=name)
        return None


def plain(value):
    """The student's answer as JSON: numpy arrays and numbers become lists and numbers, tuples
    lists, a dict {"pairs": [[key, value], ...]}; anything else raises TypeError."""
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if hasattr(value, "tolist") and callable(value.tolist):     # numpy arrays and scalars
        return plain(value.tolist())
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, dict):
        return {"pairs": [[plain(k), plain(v)] for k, v in value.items()]}
    raise TypeError(f"returned a {type(value).__name__}, not numbers")


def _error(exc: BaseException) -> str:
    if isinstance(exc, NotImplementedError):
        return "NotImplementedError: not done yet"
    tb = traceback.extract_tb(exc.__traceback__)
    where = next((f" (line {f.lineno})" for f in reversed(tb) if f.filename.endswith(".py")
                  and "runner.py" not in f.filename), "")
    return f"{type(exc).__name__}: {exc}{where}"


def run(job: dict) -> list[dict]:
    """Import the module and call its function on every case's arguments."""
    sys.path.insert(0, job["workspace"])
    path = f"{job['workspace']}/{job['module']}.py"
    spec = importlib.util.spec_from_file_location(job["module"], path)
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
        function = getattr(module, job["function"])
    except BaseException as exc:  # noqa: BLE001 - the student's import, whatever it raises
        return [{"error": f"importing {job['module']}.py: {_error(exc)}"}] * len(job["args"])
    out = []
    for args in job["args"]:
        try:
            out.append({"value": plain(function(*args))})
        except BaseException as exc:  # noqa: BLE001 - one case lost, not the task
            out.append({"error": _error(exc)})
    return out


def main(argv: list[str]) -> int:
    here = os.path.dirname(os.path.abspath(__file__))
    sys.path[:] = [p for p in sys.path if os.path.abspath(p or ".") != here]   # students' win
    sys.meta_path.insert(0, Withheld())
    job = json.load(sys.stdin)
    real_stdout, sys.stdout = sys.stdout, sys.stderr    # a student's prints are not results
    results = run(job)
    sys.stdout = real_stdout
    with open(argv[1], "w", encoding="utf-8") as f:
        json.dump(results, f)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
