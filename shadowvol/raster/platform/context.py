"""The one place that creates an OpenGL context: headless, through EGL (no display needed).

Everything GL in shadowvol runs on a context made by `create_context`.  Mesa's llvmpipe (a CPU
rasterizer) is enough; a GPU vendor's EGL driver works unchanged.
"""

from __future__ import annotations

import contextlib
import os

import moderngl

from shadowvol.errors import RenderError

REQUIRED_GL_VERSION = 450  # geometry shaders with `precise`, glClipControl-era core profile

INSTALL_HINT = ("install an EGL driver with OpenGL 4.5: on Debian/Ubuntu "
                "`apt-get install libegl1 libgl1-mesa-dri` (Mesa), or your GPU vendor's EGL driver")


class ContextError(RenderError):
    """No usable OpenGL 4.5 context: EGL, the driver or the GL version is missing."""


class ForkedContextError(ContextError):
    """A process forked after its parent made a GL context tried to make one: EGL's state
    (the driver's threads, the display connection) does not survive fork, and the call would
    hang for ever."""


FORK_ADVICE = ("this process was forked after its parent made an OpenGL context, and EGL cannot "
               "be used in such a child (it would hang); start workers with "
               "multiprocessing.get_context('spawn') or 'forkserver', or make the first context "
               "in the child, not the parent")


class _ProcessState:
    """Which process made a context here: a process fact, not a renderer's state."""
    made_in_pid: int | None = None


def _check_not_forked() -> None:
    made = _ProcessState.made_in_pid
    if made is not None and made != os.getpid():
        raise ForkedContextError(FORK_ADVICE)


def check_not_forked() -> None:
    """Raise ForkedContextError in a child forked after its parent made a context, before
    anything (EGL device queries included) can hang there."""
    _check_not_forked()


def create_context(device: int | None = None) -> moderngl.Context:
    """A new standalone OpenGL >= 4.5 core context on EGL.

    `device`: the index of the EGL device to render on (in eglQueryDevicesEXT's order; see
    `shadowvol.raster.platform.egl` for listing them, `shadowvol.batch.egl` for choosing one), or
    None for glcontext's default (device 0, or $GLCONTEXT_DEVICE_INDEX).  CUDA_VISIBLE_DEVICES does
    not select an EGL device.  The caller owns the context and must `release()` it.  Raises ContextError naming what to
    install when libEGL, a driver, or GL 4.5 is missing, and one saying how many devices there
    are when `device` is not one of them.
    """
    _check_not_forked()
    where = {} if device is None else {"device_index": int(device)}
    try:
        ctx = moderngl.create_context(standalone=True, backend="egl",
                                      require=REQUIRED_GL_VERSION, **where)
    except Exception as exc:  # glcontext raises bare Exceptions with the loader's message
        text = str(exc).strip() or type(exc).__name__
        if "device index" in text and device is None:  # no EGL device at all
            raise ContextError(f"cannot create a headless EGL context (the EGL driver lists no "
                               f"device: {text}); {INSTALL_HINT}") from None
        if "device index" in text:  # glcontext: "requested device index 3, but found 1 devices"
            raise ContextError(f"there is no EGL device {device} ({text})") from None
        if "version" in text.lower() or "require" in text.lower():
            raise ContextError(f"OpenGL {REQUIRED_GL_VERSION // 100}.{REQUIRED_GL_VERSION % 100 // 10}"
                               f" is not available ({text}); {INSTALL_HINT}") from None
        raise ContextError(f"cannot create a headless EGL context ({text}); "
                           f"{INSTALL_HINT}") from None
    if ctx.version_code < REQUIRED_GL_VERSION:
        version = ctx.info.get("GL_VERSION", str(ctx.version_code))
        ctx.release()
        raise ContextError(f"the EGL driver offers OpenGL {version}, shadowvol needs 4.5; "
                           f"{INSTALL_HINT}")
    _ProcessState.made_in_pid = os.getpid()
    return ctx


def make_current(ctx: moderngl.Context) -> None:
    """Make `ctx` the thread's current context (raw GL calls go to the current context).

    moderngl's `with ctx:` would do it, but glcontext's EGL `__exit__` does not restore the
    previous context: it leaves NO context current (checked with eglGetCurrentContext, glcontext
    3.1).  So we enter and never exit: the renderer's context simply stays current.
    Raises ForkedContextError in a child forked after the context was made.
    """
    _check_not_forked()
    ctx.__enter__()


# glGetError returns one flag a call, and a driver keeps a few: this many calls clear them all
MAX_ERROR_FLAGS = 16


def clear_errors(ctx: moderngl.Context) -> list[str]:
    """Read and so clear the context's GL error flags; returns what was set (["GL_OUT_OF_..."]),
    [] when none was.  A failed frame calls it so that its errors never reach the next one,
    which would read them as its own."""
    found = []
    for _ in range(MAX_ERROR_FLAGS):
        error = ctx.error
        if error == "GL_NO_ERROR":
            break
        found.append(error)
    return found


@contextlib.contextmanager
def errors_cleared_on_failure(ctx: moderngl.Context):
    """Whatever raises inside leaves the context's GL error flags clear (`clear_errors`)."""
    try:
        yield
    except BaseException:
        clear_errors(ctx)
        raise
