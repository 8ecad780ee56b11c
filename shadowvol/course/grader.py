"""`shadowvol course grade`: a student's workspace graded against the project's own code.

Each task runs in its own process (`runner.py`) with a time limit, so an endless loop, a crash
or a module that does not import costs that task only.  The cases and their answers come from
the project's implementation (`tasks_rays`, `tasks_light`, `tasks_shadows`); the grading
process never sees an expected answer.  A task scores its points times the share of its cases
passed; the table names, for the first failing case of each task, its inputs, the expected
answer and the student's, in words.  `gradescope` gives the same as Gradescope's
results.json (`score`, `max_score`, `tests`).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from shadowvol.course import tasks_light, tasks_rays, tasks_shadows
from shadowvol.course.runner import plain
from shadowvol.course.task import Case, Task

TASKS: list[Task] = tasks_rays.TASKS + tasks_light.TASKS + tasks_shadows.TASKS
# Seconds one task's process may run: the cases take milliseconds, numpy's import about 0.2 s,
# on a machine busy with a whole class's grading a few seconds.
DEFAULT_TIMEOUT = 10.0
RUNNER = Path(__file__).with_name("runner.py")


@dataclass(frozen=True)
class TaskResult:
    task: Task
    passed: int
    total: int
    failure: str | None     # the first failing case (or why the task failed), in words

    @property
    def score(self) -> float:
        return round(self.task.points * self.passed / self.total, 2) if self.total else 0.0


@dataclass(frozen=True)
class Report:
    results: list[TaskResult]

    @property
    def score(self) -> float:
        return round(sum(r.score for r in self.results), 2)

    @property
    def max_score(self) -> int:
        return sum(r.task.points for r in self.results)

    @property
    def full_marks(self) -> bool:
        return all(r.passed == r.total for r in self.results)


def check_workspace(workspace: Path) -> None:
    """Raise ValueError (one line) unless `workspace` is a folder holding a task module."""
    if not workspace.is_dir():
        raise ValueError(f"{workspace}: no such folder (shadowvol course new {workspace} "
                         f"makes a workspace)")
    if not any((workspace / f"{t.name}.py").is_file() for t in TASKS):
        raise ValueError(f"{workspace}: holds none of the task files ({TASKS[0].name}.py, "
                         f"..., {TASKS[-1].name}.py): not a course workspace")


def grade(workspace: Path, timeout: float = DEFAULT_TIMEOUT, tasks=None) -> Report:
    """Every task of `tasks` (default: all) graded in its own process."""
    workspace = Path(workspace)
    check_workspace(workspace)
    return Report([grade_task(workspace, t, timeout) for t in (tasks or TASKS)])


def grade_task(workspace: Path, task: Task, timeout: float = DEFAULT_TIMEOUT) -> TaskResult:
    cases = task.cases()
    if not (workspace / f"{task.name}.py").is_file():
        return TaskResult(task, 0, len(cases), f"{task.name}.py is missing")
    answers = _run(workspace, task, cases, timeout)
    if isinstance(answers, str):
        return TaskResult(task, 0, len(cases), answers)
    return judge(task, cases, answers)


def _run(workspace: Path, task: Task, cases: list[Case], timeout: float) -> list[dict] | str:
    """The student's answers from a grading process, or why there are none."""
    job = {"workspace": str(workspace.resolve()), "module": task.name,
           "function": task.function, "args": [list(c.args) for c in cases]}
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1", "OMP_NUM_THREADS": "1",
           "OPENBLAS_NUM_THREADS": "1"}
    with tempfile.TemporaryDirectory(prefix="shadowvol-grade-") as tmp:
        out = Path(tmp) / "answers.json"
        try:
            done = subprocess.run([sys.executable, str(RUNNER), str(out)], input=json.dumps(job),
                                  capture_output=True, text=True, timeout=timeout,
                                  cwd=workspace, env=env)
        except subprocess.TimeoutExpired:
            return (f"ran past the time limit of {timeout:g} s (an endless loop?): stopped, "
                    f"the task scores 0")
        if done.returncode != 0 or not out.is_file():
            last = (done.stderr.strip().splitlines() or ["no message"])[-1]
            return f"the grading process died (exit status {done.returncode}): {last}"
        answers = json.loads(out.read_text(encoding="utf-8"))
    if not isinstance(answers, list) or len(answers) != len(cases):
        return "the grading process gave no answer for every case"
    return answers


def judge(task: Task, cases: list[Case], answers: list[dict]) -> TaskResult:
    """Compare the answers ({"value": ...} or {"error": ...}, one per case) with the cases."""
    passed, failure = 0, None
    for k, (case, answer) in enumerate(zip(cases, answers), 1):
        if "error" in answer:
            why, got = answer["error"], f"raised {answer['error']}"
        else:
            why = task.check(case, answer["value"])
            got = task.show(answer["value"])
        if why is None:
            passed += 1
        elif failure is None:
            failure = "\n".join([
                f"case {k} of {len(cases)}: {case.label}",
                f"  input:    {task.show_args(case.args)}",
                f"  expected: {task.show(case.expected)}",
                f"  got:      {got}",
                *([f"  wrong:    {why}"] if task.explains and "error" not in answer
                  else [])])
    return TaskResult(task, passed, len(cases), failure)


def evaluate(task: Task, function, cases: list[Case] | None = None) -> TaskResult:
    """`function` judged on the task's cases (or `cases`) in THIS process: no time limit, no
    isolation; for the tests' many broken and mutated solutions (the cases, the answers' JSON
    and the judging are `grade`'s)."""
    cases = task.cases() if cases is None else cases
    answers = []
    for case in cases:
        try:
            value = function(*json.loads(json.dumps(list(case.args))))
            answers.append(json.loads(json.dumps({"value": plain(value)})))
        except Exception as exc:  # noqa: BLE001 - a broken solution's error is its answer
            answers.append({"error": f"{type(exc).__name__}: {exc}"})
    return judge(task, cases, answers)


# ---------------------------------------------------------------------------------------------
# The table and Gradescope's results
# ---------------------------------------------------------------------------------------------

def table(report: Report) -> str:
    """The grade as a table (task, points, cases passed), then each task's first failure."""
    width = max(len(r.task.name) for r in report.results)
    title = max(len(r.task.title) for r in report.results)
    lines = [f"{'task':<{width + 4}}  {'':<{title}}  {'points':>11}  {'cases':>7}"]
    for i, r in enumerate(report.results, 1):
        mark = "" if r.passed == r.total else "  ✗"
        lines.append(f"{i:>2}. {r.task.name:<{width}}  {r.task.title:<{title}}  "
                     f"{_points(r.score):>6}/{r.task.points:<4}  {r.passed:>3}/{r.total:<3}"
                     f"{mark}")
    lines.append(f"{'total':<{width + 4}}  {'':<{title}}  "
                 f"{_points(report.score):>6}/{report.max_score:<4}")
    for r in report.results:
        if r.failure:
            lines += ["", f"{r.task.name} ({r.task.name}.py, {r.task.function}): "
                          + r.failure.splitlines()[0], *r.failure.splitlines()[1:]]
    return "\n".join(line.rstrip() for line in lines)


def _points(x: float) -> str:
    return f"{x:g}"


def gradescope(report: Report) -> dict:
    """Gradescope's results.json: the total, and one test per task with its first failure."""
    return {"score": report.score, "max_score": report.max_score,
            "tests": [{"name": f"{r.task.name}: {r.task.title}", "score": r.score,
                       "max_score": r.task.points,
                       "output": f"{r.passed}/{r.total} cases passed"
                                 + (f"\n{r.failure}" if r.failure else "")}
                      for r in report.results]}
