"""The project's error classes that say which exit status they mean (shadowvol.cli.status).

`SceneError` (bad input) lives with the scene model; these are the rest, GL-free so that the
ray tracer and the CLI can name them without importing GL.
"""

from __future__ import annotations

import contextlib
import importlib


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
