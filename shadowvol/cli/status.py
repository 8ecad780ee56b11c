"""The one exit-status table of both command-line tools, `shadowvol` and `raytrace`.

Every command returns one of these statuses (`shadowvol.errors` decides them), and its --help
prints `EPILOG`.  `report` turns an exception into one line on stderr and its status, so no
command prints a traceback for an error it can name.  GL-free.
"""

from __future__ import annotations

import contextlib
import sys
import warnings

from shadowvol import signals
from shadowvol.errors import one_line_warning
from shadowvol.errors import (  # noqa: F401 - the statuses, named here for the commands
    BAD_INPUT,
    INTERRUPTED,
    OK,
    OVER_BUDGET,
    RENDER_FAILED,
    TERMINATED,
    message,
    status_of,
)

TABLE = (
    (OK, "success"),
    (OVER_BUDGET, "a comparison over its budget (compare --max-interior), a grade short of "
                  "full marks (course grade), a student's image not the reference's (course "
                  "render)"),
    (BAD_INPUT, "bad input: a scene file, a mesh, an argument, an output path, a scene beyond "
                "the documented limits or an image over the memory budget, or a missing "
                "optional extra (named with the pip command that installs it)"),
    (RENDER_FAILED, "rendering failed: no usable EGL/OpenGL 4.5, a GL error, out of memory, a "
                    "stencil overflow"),
    (INTERRUPTED, "interrupted (Ctrl-C)"),
    (TERMINATED, "terminated (SIGTERM)"),
)

EPILOG = "exit status: " + "; ".join(f"{code} {text}" for code, text in TABLE) + \
    ".  Outputs are written atomically: a failed or interrupted command leaves no half file."


def report(exc: BaseException, prefix: str = "") -> int:
    """Print `error: PREFIXmessage` on stderr and return the exception's status; re-raise an
    exception that has none."""
    exc = signals.pending() or exc  # an interrupt may surface as what it broke
    status = status_of(exc)
    if status is None:
        raise exc
    print(f"error: {prefix}{message(exc)}", file=sys.stderr)
    return status


def run(command, args) -> int:
    """Call `command(args)` with Ctrl-C and SIGTERM handled (`shadowvol.signals`) and turn what
    it raises into a status (see `report`); an interrupt that something swallowed on the way
    still ends in its status."""
    with signals.handled(), warnings.catch_warnings():
        warnings.showwarning = one_line_warning   # "warning: ...", one line each
        try:
            code = command(args)
            if code not in (INTERRUPTED, TERMINATED):  # else the command reported it already
                signals.raise_pending()
            return code
        except (Exception, KeyboardInterrupt, signals.Terminated) as exc:  # noqa: BLE001
            return report(exc)  # report re-raises what has no status (a bug)


def main(build_parser, argv) -> int:
    """A tool's `main`: parse `argv` with the parser `build_parser()` makes and `run` the
    command it names (an interrupt while parsing is reported too)."""
    try:
        args = build_parser().parse_args(argv)
    except KeyboardInterrupt as exc:
        return report(exc)
    return run(args.func, args)


@contextlib.contextmanager
def naming(scene_path):
    """A SceneError raised inside without a file (the Renderer's refusals: `image`, `objects`,
    which it knows only as a Scene) names `scene_path`."""
    try:
        yield
    except ValueError as exc:
        scene = sys.modules.get("shadowvol.scene")
        if scene is not None and isinstance(exc, scene.SceneError) and exc.file is None:
            raise exc.in_file(str(scene_path)) from None
        raise
