"""`shadowvol course`: the course's exercises as assignments.

    shadowvol course new DIR                  a student's workspace: one module per task, stubs
    shadowvol course grade DIR [--json F]     grade it: the table; exit 0 only at full marks
    shadowvol course solutions DIR            the reference solutions (they grade full marks)
    shadowvol course render DIR SCENE -o P    the Whitted tracer with the student's ray-sphere
                                              and shadow test, beside its own image
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from shadowvol.cli import options, output_paths, status
from shadowvol.course import grader, student_render, workspace
from shadowvol.errors import InputError
from shadowvol.io import save_png, write_bytes
from shadowvol.scenefile import load_scene

EPILOG = """\
A teacher hands out `course new DIR` (or a copy of it), collects the students' folders and
runs `course grade` on each; `--json` writes Gradescope's results.json for an autograder.
Each task runs in its own process with a time limit (--timeout), so an endless loop or a
crash costs that task only.  The cases and their answers come from the project's own code.
"""


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = options.command(subparsers, "course", help="the course's exercises: hand out, grade",
                       description="The lecture's exercises as assignments, graded against "
                                   "the project's own implementation.",
                       epilog=EPILOG + "\n" + status.EPILOG)
    sub = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    new = options.command(sub, "new", help="write a student's workspace (stubs)",
                         description="One Python module per task: the function to write, its "
                                     "docstring and an example.  DIR must be new or empty.")
    new.add_argument("folder", metavar="DIR", type=Path, help="the workspace to create")
    new.set_defaults(func=command_new, solved=False)
    sol = options.command(sub, "solutions", help="write the reference solutions",
                         description="The same modules, every function filled: the "
                                     "teacher's copy.  DIR must be new or empty.")
    sol.add_argument("folder", metavar="DIR", type=Path, help="the folder to create")
    sol.set_defaults(func=command_new, solved=True)
    grade = options.command(sub, "grade", help="grade a workspace",
                           description="Grade every task of a workspace on hidden cases.",
                           epilog="exit status: 0 full marks; 1 short of them; 2 bad input "
                                  "(no such folder, not a workspace, a bad --json path).")
    grade.add_argument("folder", metavar="DIR", type=Path, help="the student's workspace")
    grade.add_argument("--json", metavar="F", type=Path, default=None,
                       help="also write the grade as Gradescope's results.json to F")
    grade.add_argument("--timeout", metavar="S", type=float, default=grader.DEFAULT_TIMEOUT,
                       help=f"seconds each task may run (default {grader.DEFAULT_TIMEOUT:g})")
    grade.set_defaults(func=command_grade)
    ren = options.command(sub, "render", help="render with the student's ray-sphere and shadow "
                                             "test",
                         description="The Whitted tracer with the workspace's "
                                     "ray_sphere.intersect and shadow_ray.in_shadow for the "
                                     "spheres, beside the tracer's own image, the pixels that "
                                     "differ marked.")
    ren.add_argument("folder", metavar="DIR", type=Path, help="the student's workspace")
    options.scene(ren)
    options.output(ren, "PNG", "the picture: yours | the reference | where they differ")
    ren.add_argument("--size", metavar="WxH", default=None,
                     help="the image size (default: the scene's, scaled to 240 pixels wide)")
    ren.add_argument("--timeout", metavar="S", type=float,
                     default=student_render.DEFAULT_TIMEOUT,
                     help=f"seconds the student's render may run (default "
                          f"{student_render.DEFAULT_TIMEOUT:g})")
    ren.set_defaults(func=command_render)
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
        output_paths.check({"json": args.json}, {"json": "--json"})
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


def _size(text: str | None, scene) -> tuple[int, int]:
    if text is None:
        return 240, max(1, round(240 * scene.height / scene.width))
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise InputError("--size", f"expected WxH, e.g. 240x180, got {text!r}") from None
    if not (1 <= w <= 4096 and 1 <= h <= 4096):
        raise InputError("--size", f"must be 1..4096 a side, got {text!r}")
    return w, h


def command_render(args) -> int:
    output_paths.check({"image": Path(args.output)}, {"image": "-o"})
    if not (math.isfinite(args.timeout) and args.timeout > 0):
        raise InputError("--timeout", f"must be a positive number of seconds, got "
                                      f"{args.timeout:g}")
    try:
        grader.check_workspace(args.folder)
    except ValueError as exc:
        raise InputError("DIR", str(exc)) from None
    scene = load_scene(args.scene)
    w, h = _size(args.size, scene)
    pair = student_render.render_pair(args.folder, args.scene, scene.replace(width=w, height=h),
                                      args.timeout)
    save_png(args.output, pair.picture())
    for note in pair.notes:
        print(note)
    print(f"{int(pair.differ.sum())} of {w * h} pixels differ from the reference; wrote "
          f"{args.output}")
    # 0 only when the student's own functions drew the reference's image
    return status.OK if not pair.differ.any() and not pair.notes else status.OVER_BUDGET
