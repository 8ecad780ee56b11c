"""`raytrace exercise`: a worked exercise of the course, printed, and drawn with -o."""

from __future__ import annotations

import io
import sys
from pathlib import Path

from raytrace import exercise
from shadowvol.cli import options, output_paths, status
from shadowvol.course.exercise_picture import plane_figure, tir_figure
from shadowvol.io import atomic_write


def _plane():
    s = exercise.solve_plane()
    return exercise.plane_text(s), plane_figure(s)


def _tir():
    rays = exercise.solve_tir()
    return exercise.tir_text(rays), tir_figure(rays)


EXERCISES = {"plane": _plane, "tir": _tir}


def add_parser(sub) -> None:
    e = options.command(sub, "exercise", help="a worked exercise of the course, printed and drawn",
                       description="Print the worked solution of one of the course's "
                                   "exercises, computed with the ray tracer's own formulas, "
                                   "and optionally draw it.  plane: the ray (5,1) + λ(−1,3) "
                                   "against the plane through (2,2) with normal (1,−1).  tir: "
                                   "Snell's law from glass into air, past the critical angle.")
    e.add_argument("name", choices=tuple(EXERCISES), metavar="NAME",
                   help="the exercise: " + ", ".join(EXERCISES))
    options.output(e, "PNG", "also draw the exercise's 2D picture", required=False)
    e.set_defaults(func=command)


def command(args) -> int:
    """Print the worked solution, draw it with -o."""
    if args.output:
        output_paths.check({"picture": Path(args.output)}, {"picture": "-o"}, "raytrace")
    text, fig = EXERCISES[args.name]()
    print(text)
    if args.output:
        buf = io.BytesIO()
        fig.savefig(buf, format="png")
        with atomic_write(args.output) as f:
            f.write(buf.getvalue())
        print(f"wrote {args.output}", file=sys.stderr)
    return status.OK
