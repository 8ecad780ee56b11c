"""`shadowvol course new` and `shadowvol course solutions`: a student's workspace, one Python
module per task, written from the reference solutions (`shadowvol/course/solutions/`).

`new` keeps each module's docstrings, constants and imports and replaces the body of every
graded function by `raise NotImplementedError`; helper functions (named with a leading `_`)
are the solution's own and are left out.  `solutions` writes the modules as they are.  Both
write a README.md listing the tasks, and refuse a folder that is not empty.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

from shadowvol.course.grader import TASKS
from shadowvol.io import write_bytes

SOLUTIONS = Path(__file__).with_name("solutions")


def solution_source(name: str) -> str:
    """The reference solution of task `name`, as its module's text."""
    return (SOLUTIONS / f"{name}.py").read_text(encoding="utf-8")


def stub(source: str) -> str:
    """The module with every public top-level function's body after its docstring replaced by
    `raise NotImplementedError(...)`, and the private ones (`_name`) left out."""
    tree = ast.parse(source)
    lines = source.splitlines()
    cut: dict[int, tuple[int, str | None]] = {}    # first line (0-based) -> (end, replacement)
    for node in tree.body:
        if not isinstance(node, ast.FunctionDef):
            continue
        first = min([node.lineno] + [d.lineno for d in node.decorator_list]) - 1
        if node.name.startswith("_"):
            cut[first] = (node.end_lineno, None)
            continue
        doc = node.body[0]
        if not (isinstance(doc, ast.Expr) and isinstance(doc.value, ast.Constant)):
            raise ValueError(f"solution function {node.name} has no docstring")
        cut[doc.end_lineno] = (node.end_lineno,
                               f'    raise NotImplementedError("{node.name}: your code here")')
    out, i = [], 0
    while i < len(lines):
        if i in cut:
            end, replacement = cut[i]
            if replacement is not None:
                out.append(replacement)
            i = end
            continue
        out.append(lines[i])
        i += 1
    text = "\n".join(out).rstrip() + "\n"
    return re.sub(r"\n{4,}", "\n\n\n", text)


def readme(solved: bool) -> str:
    """The workspace's README.md: the tasks, their points, how to grade."""
    rows = "\n".join(f"| {i} | `{t.name}.py` | `{t.function}` | {t.title} | {t.points} |"
                     for i, t in enumerate(TASKS, 1))
    head = ("# The course's exercises: the reference solutions\n\nEvery function filled in; "
            "they grade full marks.\n" if solved else
            "# The course's exercises\n\nFill in the function of each module: its docstring "
            "says what it takes, what it returns and the lecture's formula, with a small "
            "example.  Keep the names and the files; add helpers as you like.  numpy is "
            "there; the example runs with `python -m doctest FILE.py`.\n")
    return (f"{head}\n| # | file | function | task | points |\n|---|---|---|---|---|\n{rows}\n\n"
            f"Grade it with `shadowvol course grade .` (each task runs in its own process "
            f"with a time limit; the table shows the first failing case of each task).\n")


def write_workspace(folder: Path, solved: bool = False) -> list[Path]:
    """Write one module per task (stubs, or the solutions when `solved`) and README.md into
    `folder`, which must not exist or be empty; return the files written.  Raises ValueError
    (one line) for a folder that holds anything."""
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise ValueError(f"{folder}: exists and is not a folder")
    if folder.is_dir() and any(folder.iterdir()):
        raise ValueError(f"{folder}: not empty; refusing to overwrite it (give a new folder)")
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for task in TASKS:
        text = solution_source(task.name)
        path = folder / f"{task.name}.py"
        write_bytes(path, (text if solved else stub(text)).encode("utf-8"))
        written.append(path)
    write_bytes(folder / "README.md", readme(solved).encode("utf-8"))
    return written + [folder / "README.md"]
