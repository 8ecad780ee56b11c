"""The viewer's GL side (`shadowvol view`): moderngl on the window's own context, and the blit
that shows a composed picture in the window.

The window (pyglet, `shadowvol.view`) makes its context (GLX under X11, EGL for pyglet's
headless window) and makes it current;
`attach` wraps it for moderngl, and the renderer then renders into its own offscreen target in
that context exactly as on EGL (`gl` loads its raw GL functions from the current
context).  The frame is read back, composed with the side panel on the CPU, and blitted one
texel per pixel, so the window shows exactly the offscreen render's pixels.
"""

from __future__ import annotations

import ctypes
import ctypes.util

import moderngl
import numpy as np

from shadowvol.raster import glsl
from shadowvol.raster.platform.context import REQUIRED_GL_VERSION, ContextError


class _EglLoader:
    """GL functions of the current EGL context, for moderngl (`create_context(context=...)`):
    glcontext's own EGL backend only makes contexts of its own, it cannot detect one."""

    def __init__(self):
        self._egl = ctypes.CDLL(ctypes.util.find_library("EGL") or "libEGL.so.1")
        self._egl.eglGetProcAddress.restype = ctypes.c_void_p
        self._egl.eglGetProcAddress.argtypes = [ctypes.c_char_p]

    def load_opengl_function(self, name: str) -> int:
        return self._egl.eglGetProcAddress(name.encode()) or 0

    def release(self) -> None:
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        pass


def attach(egl: bool = False) -> moderngl.Context:
    """A moderngl context for the GL context current on this thread (the window's); the
    window owns the context itself.  `egl`: the window's context is EGL (pyglet's headless
    window), else the platform's default (GLX under X11)."""
    try:
        ctx = moderngl.create_context(require=REQUIRED_GL_VERSION,
                                      **({"context": _EglLoader()} if egl else {}))
    except Exception as exc:  # glcontext raises bare Exceptions
        raise ContextError(f"the window's OpenGL context is unusable ({exc}); shadowvol view "
                           "needs OpenGL 4.5") from None
    return ctx


class Blit:
    """Shows an (H, W, 3) uint8 picture in the window's default framebuffer.  `release()`."""

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        self.program = glsl.program(ctx, "blit.vert", "blit.frag")
        self.vao = ctx.vertex_array(self.program, [])
        self.texture = None

    def show(self, picture: np.ndarray) -> None:
        """Draw `picture` (row 0 at the top) to the window, one texel per pixel."""
        h, w = picture.shape[:2]
        if self.texture is None or self.texture.size != (w, h):
            if self.texture is not None:
                self.texture.release()
            self.texture = self.ctx.texture((w, h), 3, dtype="f1")
            self.texture.filter = moderngl.NEAREST, moderngl.NEAREST
        self.texture.write(np.ascontiguousarray(picture, np.uint8).tobytes())
        screen = self.ctx.screen
        screen.use()
        self.ctx.viewport = (0, 0, w, h)
        self.ctx.disable(moderngl.DEPTH_TEST | moderngl.BLEND | moderngl.CULL_FACE)
        self.texture.use(0)
        self.program["u_picture"] = 0
        self.vao.render(moderngl.TRIANGLES, vertices=3)

    def read_window(self, width: int, height: int) -> np.ndarray:
        """(height, width, 3) uint8: the window's back buffer as drawn, row 0 at the top."""
        # copied to an offscreen framebuffer first: moderngl reads a framebuffer's colour
        # attachment 0, which the window's default framebuffer does not have (a GL error)
        colour = self.ctx.renderbuffer((width, height), 4)
        fbo = self.ctx.framebuffer(color_attachments=[colour])
        try:
            self.ctx.copy_framebuffer(fbo, self.ctx.screen)
            raw = fbo.read(viewport=(0, 0, width, height), components=3, alignment=1)
        finally:
            fbo.release()
            colour.release()
        return np.frombuffer(raw, np.uint8).reshape(height, width, 3)[::-1].copy()

    def release(self) -> None:
        for obj in (self.vao, self.program, self.texture):
            if obj is not None:
                obj.release()
        self.texture = None
