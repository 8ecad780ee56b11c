"""pyrender's EGL context beside ours: the raw EGL calls the pyrender peer
(`shadowvol.compare.pyrender_peer`) needs, kept in the GL wing.

pyrender's `OffscreenRenderer.delete()` calls `eglTerminate` on the EGL display, which is shared
by every EGL user in the process (pyrender issue #223, "re-create OffscreenRenderer":
EGL_BAD_DISPLAY), so it would kill a moderngl context living beside it, and pyrender leaves its
own context current.  `offscreen` tears the renderer down without terminating the display and
makes the caller's context current again.
"""

from __future__ import annotations

import contextlib
import ctypes
import os


def egl_current():
    """The calling thread's current EGL (display, draw, read, context), or None."""
    if os.environ.get("PYOPENGL_PLATFORM") != "egl":
        return None
    from OpenGL import EGL
    ctx = EGL.eglGetCurrentContext()
    if not ctypes.cast(ctx, ctypes.c_void_p).value:
        return None
    return (EGL.eglGetCurrentDisplay(), EGL.eglGetCurrentSurface(EGL.EGL_DRAW),
            EGL.eglGetCurrentSurface(EGL.EGL_READ), ctx)


@contextlib.contextmanager
def offscreen(pyrender, width: int, height: int):
    """A `pyrender.OffscreenRenderer` that leaves the process's EGL state as it found it
    (`pyrender`: the module, imported with its shims by `shadowvol.compare.pyrender_peer`)."""
    saved = egl_current()
    renderer = pyrender.OffscreenRenderer(width, height)
    try:
        yield renderer
    finally:
        platform = renderer._platform
        if os.environ.get("PYOPENGL_PLATFORM") == "egl" and platform is not None:
            # pyrender's delete() would eglTerminate the shared display (pyrender#223): free
            # the GL objects and the context ourselves, and keep the display.
            from OpenGL import EGL
            platform.make_current()
            renderer._renderer.delete()
            EGL.eglMakeCurrent(platform._egl_display, EGL.EGL_NO_SURFACE, EGL.EGL_NO_SURFACE,
                               EGL.EGL_NO_CONTEXT)
            EGL.eglDestroyContext(platform._egl_display, platform._egl_context)
            platform._egl_context = platform._egl_display = None
            renderer._renderer = renderer._platform = None
        else:
            renderer.delete()
        if saved is not None:
            restore(saved)


def restore(saved) -> None:
    """Make the context that was current before pyrender's current again.  A context that was
    released while current (a one-shot `shadowvol.render`, a user's own OffscreenRenderer) is
    still reported current but is gone once another was made current: then leave none current,
    as its owner left it, instead of failing with EGL_BAD_CONTEXT."""
    from OpenGL import EGL, error

    try:
        EGL.eglMakeCurrent(*saved)
    except error.GLError:
        EGL.eglMakeCurrent(saved[0], EGL.EGL_NO_SURFACE, EGL.EGL_NO_SURFACE,
                           EGL.EGL_NO_CONTEXT)
