"""`shadowvol course`: the course's exercises as assignments.

    shadowvol course new DIR                  a student's workspace: one module per task, stubs
    shadowvol course grade DIR [--json F]     grade it: the table; exit 0 only at full marks
    shadowvol course solutions DIR            the reference solutions (they grade full marks)
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from shadowvol.cli import args as blocks
from shadowvol.cli import outputs, status
from shadowvol.course import grader, workspace
from shadowvol.io import write_bytes

EPILOG = """\
A teacher hands out `course new DIR` (or a copy of it), collects the students' folders and
runs `course grade` on each; `--json` writes Gradescope's results.json for an autograder.
Each task runs in its own process with a time limit (--timeout), so an endless loop or a
crash costs that task only.  The cases and their answers come from the project's own code.
"""


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = blocks.command(subparsers, "course", help="the course's exercises: hand out, grade",
                       description="The lecture's exercises as assignments, graded against "
                                   "the project's own implementation.",
                       epilog=EPILOG + "\n" + status.EPILOG)
    sub = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    new = blocks.command(sub, "new", help="write a student's workspace (stubs)",
                         description="One Python module per task: the function to write, its "
                                     "docstring and an example.  DIR must be new or empty.")
    new.add_argument("folder", metavar="DIR", type=Path, help="the workspace to create")
    new.set_defaults(func=command_new, solved=False)
    sol = blocks.command(sub, "solutions", help="write the reference solutions",
                         description="The same modules, every function filled: the "
                                     "teacher's copy.  DIR must be new or empty.")
    sol.add_argument("folder", metavar="DIR", type=Path, help="the folder to create")
    sol.set_defaults(func=command_new, solved=True)
    grade = blocks.command(sub, "grade", help="grade a workspace",
                           description="Grade every task of a workspace on hidden cases.",
                           epilog="exit status: 0 full marks; 1 short of them; 2 bad input "
                                  "(no such folder, not a workspace, a bad --json path).")
    grade.add_argument("folder", metavar="DIR", type=Path, help="the student's workspace")
    grade.add_argument("--json", metavar="F", type=Path, default=None,
                       help="also write the grade as Gradescope's results.json to F")
    grade.add_argument("--timeout", metavar="S", type=float, default=grader.DEFAULT_TIMEOUT,
                       help=f"seconds each task may run (default {grader.DEFAULT_TIMEOUT:g})")
    grade.set_defaults(func=command_grade)
    return p


def command_new(args) -> int:
    """`course new` and `course solutions`."""
    try:
        written = workspace.write_workspace(args.folder, solved=args.solved)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return status.BAD_INPUT
    what = "reference solutions" if args.solved else "tasks"
    print(f"wrote {len(written) - 1} {what} and README.md to {args.folder}")
    return status.OK


def command_grade(args) -> int:
    if args.json is not None:
        outputs.check({"json": args.json}, {"json": "--json"})
    if not (math.isfinite(args.timeout) and args.timeout > 0):
        print(f"error: --timeout must be a positive number of seconds, got {args.timeout:g}",
              file=sys.stderr)
        return status.BAD_INPUT
    try:
        report = grader.grade(args.folder, timeout=args.timeout)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return status.BAD_INPUT
    print(grader.table(report))
    if args.json is not None:
        text = json.dumps(grader.gradescope(report), indent=2, ensure_ascii=False)
        write_bytes(args.json, (text + "\n").encode("utf-8"))
        print(f"wrote {args.json}")
    return status.OK if report.full_marks else status.OVER_BUDGET
