"""The project's error classes and the exit status each means, with the one-line message.

Bad input has two: `InputError` (here) for a command line's flags and arguments and the
Python API's options, and `SceneError` (with the scene model, `shadowvol.checks`) for a scene,
a mesh or a job file; both exit 2, in one line.  The classes here are GL-free so that the ray
tracer, batch and the CLI can name them without importing GL.  The statuses' table and the
printing are the command line's (`shadowvol.cli.status`).
"""

from __future__ import annotations

import contextlib
import importlib
import sys

from shadowvol import signals

OK = 0
OVER_BUDGET = 1
BAD_INPUT = 2
RENDER_FAILED = 3
INTERRUPTED = 130  # 128 + SIGINT, the shell's convention
TERMINATED = 143   # 128 + SIGTERM


# A message's parts (a flag or key, the problem, a file) are cut to one line of at most this
# many characters.
MAX_MESSAGE = 400


def one_line(text: str, limit: int = MAX_MESSAGE) -> str:
    """`text` with line breaks and other control characters escaped, cut to `limit`."""
    if not text.isprintable():
        text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
    return text if len(text) <= limit else text[:limit] + "…"


class InputError(ValueError):
    """Bad command-line input: a flag, an argument or an option that cannot be used as given
    (`--size 0x0`, `--workers 0`, `-o` on a file that is not a folder), named with the flag:
    "--workers: must be a whole number >= 1, got 0".  Exit status 2, one line.  A scene, mesh
    or job file's bad key is a `shadowvol.checks.SceneError` instead."""

    def __init__(self, flag: str, problem: str):
        flag, problem = one_line(flag), one_line(problem)
        self.flag, self.problem = flag, problem
        super().__init__(f"{flag}: {problem}" if flag else problem)


class RenderError(RuntimeError):
    """Rendering failed for a reason other than the input: no usable EGL/GL, a GL error, a
    stencil count that cannot be trusted.  Exit status 3."""


class OutOfMemory(MemoryError):
    """A MemoryError that says what was being done ("writing out.png"); exit status 3."""

    def __init__(self, doing: str, detail: str = ""):
        super().__init__(doing, detail)
        self.doing, self.detail = doing, detail

    def __str__(self) -> str:
        return f"while {self.doing}" + (f" ({self.detail})" if self.detail else "")


@contextlib.contextmanager
def out_of_memory_while(doing: str):
    """Turn a MemoryError inside into OutOfMemory(doing) (one that already says what it was
    doing is left as it is)."""
    try:
        yield
    except OutOfMemory:
        raise
    except MemoryError as exc:
        raise OutOfMemory(doing, str(exc)) from None


class IgnoredMaterial(UserWarning):
    """What of a mesh file's materials the renderers do not read (normal maps, ...): one line
    naming the file (`shadowvol.scenefile_texture.warn_ignored`)."""


def one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """`warnings.showwarning` for the command line: "warning: <message>", one line on
    stderr, for every warning."""
    print(f"warning: {message}", file=sys.stderr if file is None else file)


class MissingExtra(ImportError):
    """An optional package is not installed; the message names the pip command that installs
    it.  Exit status 2 (the request cannot be met as given)."""

    def __init__(self, what: str, package: str, extra: str | None):
        install = f"pip install 'shadowvol[{extra}]'" if extra else f"pip install {package}"
        super().__init__(f"{what} needs the optional package {package!r}, which is not "
                         f"installed: {install}")
        self.name = package


def require(module: str, what: str, extra: str | None = None, package: str | None = None):
    """Import and return `module`, or raise MissingExtra naming `what` needs it."""
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        if exc.name is not None and exc.name.split(".")[0] != module.split(".")[0]:
            raise  # the package is there but broken inside: let that error speak
        raise MissingExtra(what, package or module.split(".")[0], extra) from None


def status_of(exc: BaseException) -> int | None:
    """The exit status an exception means, or None for one no command should meet (a bug).

    SceneError and moderngl.Error are looked up only where their modules were imported (the
    model and GL sit above this module): an exception of a module never loaded cannot exist."""
    scene = sys.modules.get("shadowvol.scene")
    if isinstance(exc, (InputError, MissingExtra)) or (
            scene is not None and isinstance(exc, scene.SceneError)):
        return BAD_INPUT
    if isinstance(exc, (RenderError, MemoryError)):
        return RENDER_FAILED
    moderngl = sys.modules.get("moderngl")
    if moderngl is not None and isinstance(exc, moderngl.Error):
        return RENDER_FAILED
    if isinstance(exc, OSError):
        return BAD_INPUT  # a file that cannot be read or written
    if isinstance(exc, KeyboardInterrupt):
        return INTERRUPTED
    if isinstance(exc, signals.Terminated):
        return TERMINATED
    return None


# A path in a message is cut to this many characters, keeping its start and its file name.
MAX_PATH_SHOWN = 120


def short_path(path) -> str:
    """`path` as a message shows it: whole up to MAX_PATH_SHOWN characters, else its start,
    "…" and its last name (itself cut in the middle when it is that long), so that a 5,000
    character path still names its file."""
    text = str(path)
    if len(text) <= MAX_PATH_SHOWN:
        return text
    head, sep, name = text.rpartition("/")
    if len(name) > MAX_PATH_SHOWN // 2:
        name = f"{name[:MAX_PATH_SHOWN // 4]}…{name[-MAX_PATH_SHOWN // 4:]}"
    if not sep:
        return name
    kept = head[:max(8, MAX_PATH_SHOWN - len(name) - 2)]
    return f"{kept}{'…' if len(kept) < len(head) else ''}/{name}"


def message(exc: BaseException) -> str:
    """The one line an exception is reported as (after `error: `)."""
    if isinstance(exc, MemoryError):
        # numpy's says how much it could not allocate: "Unable to allocate 3.00 GiB for ..."
        what = str(exc) if isinstance(exc, OutOfMemory) else \
            "while rendering" + (f" ({exc})" if str(exc) else "")
        return f"out of memory {what}; try a smaller image or fewer triangles"
    if isinstance(exc, KeyboardInterrupt):
        return "interrupted"
    if isinstance(exc, signals.Terminated):
        return "terminated"
    if isinstance(exc, OSError) and exc.filename is not None and exc.strerror and \
            str(exc).startswith("["):   # the OS's own "[Errno 36] ...: '<the whole path>'"
        return f"{short_path(exc.filename)}: {exc.strerror}"
    return str(exc) or type(exc).__name__
