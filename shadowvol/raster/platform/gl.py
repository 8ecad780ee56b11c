"""The raw OpenGL bindings: GL enums and entry points loaded with ctypes from the current
context, the one place (with `stencil`, which makes the calls) where raw GL lives.

moderngl has no stencil API (moderngl#676), no logic op, no clip control and no depth clamp
switch, so those few functions are loaded here through function pointers of whatever context is
current: EGL's `eglGetProcAddress` for the renderer's headless context (EGL 1.5 and Mesa return
core entry points too), GLX's `glXGetProcAddressARB` for a window's context under X11
(`shadowvol view`).
"""

from __future__ import annotations

import ctypes
import ctypes.util

from shadowvol.errors import RenderError

# GL enums (from the GL 4.5 core headers)
GL_UNSIGNED_BYTE = 0x1401
GL_STENCIL_INDEX = 0x1901
GL_DEPTH_COMPONENT = 0x1902
GL_FLOAT = 0x1406
GL_STENCIL = 0x1802
GL_COLOR = 0x1800
GL_DEPTH_STENCIL = 0x84F9
GL_FRONT = 0x0404
GL_BACK = 0x0405
GL_KEEP = 0x1E00
GL_ZERO = 0
GL_INCR_WRAP = 0x8507
GL_DECR_WRAP = 0x8508
GL_ALWAYS = 0x0207
GL_EQUAL = 0x0202
GL_NOTEQUAL = 0x0205
GL_REPLACE = 0x1E01
GL_INCR = 0x1E02
GL_STENCIL_TEST = 0x0B90
GL_DEPTH_CLAMP = 0x864F
GL_CLIP_DISTANCE0 = 0x3000
GL_PACK_ALIGNMENT = 0x0D05
GL_RENDERBUFFER = 0x8D41
GL_DEPTH32F_STENCIL8 = 0x8CAD
GL_LOWER_LEFT = 0x8CA1
GL_ZERO_TO_ONE = 0x935F
GL_CLIP_ORIGIN = 0x935C
GL_CLIP_DEPTH_MODE = 0x935D
GL_FRAMEBUFFER = 0x8D40
GL_FRAMEBUFFER_BINDING = 0x8CA6
GL_DEPTH_STENCIL_ATTACHMENT = 0x821A
GL_FRAMEBUFFER_COMPLETE = 0x8CD5
GL_RED_INTEGER = 0x8D94
GL_RG_INTEGER = 0x8228
GL_UNSIGNED_INT = 0x1405
GL_COLOR_LOGIC_OP = 0x0BF2
GL_LOGIC_OP_MODE = 0x0BF0
GL_COPY = 0x1503
GL_OR = 0x1507
GL_AND_INVERTED = 0x1504   # (NOT source) AND destination: clears the source's bits
# the stencil state queries, to save and restore it (`stencil`): per face
# func, ref, value mask, fail, depth fail, pass, write mask
FRONT_STENCIL_STATE = (0x0B92, 0x0B97, 0x0B93, 0x0B94, 0x0B95, 0x0B96, 0x0B98)
BACK_STENCIL_STATE = (0x8800, 0x8CA3, 0x8CA4, 0x8801, 0x8802, 0x8803, 0x8CA5)

_V = None  # restype void
_u = ctypes.c_uint
_i = ctypes.c_int
_p = ctypes.c_void_p
_SIGNATURES = {
    "glEnable": (_V, _u), "glDisable": (_V, _u), "glIsEnabled": (ctypes.c_ubyte, _u),
    "glGetIntegerv": (_V, _u, _p), "glGetError": (_u,),
    "glStencilFuncSeparate": (_V, _u, _u, _i, _u),
    "glStencilOpSeparate": (_V, _u, _u, _u, _u),
    "glStencilMaskSeparate": (_V, _u, _u),
    "glClearBufferiv": (_V, _u, _i, _p), "glClearBufferfv": (_V, _u, _i, _p),
    "glClearBufferuiv": (_V, _u, _i, _p), "glLogicOp": (_V, _u),
    "glClearBufferfi": (_V, _u, _i, ctypes.c_float, _i),
    "glPixelStorei": (_V, _u, _i),
    "glReadPixels": (_V, _i, _i, _i, _i, _u, _u, _p),
    "glGenRenderbuffers": (_V, _i, _p), "glDeleteRenderbuffers": (_V, _i, _p),
    "glBindRenderbuffer": (_V, _u, _u), "glRenderbufferStorage": (_V, _u, _u, _i, _i),
    "glBindFramebuffer": (_V, _u, _u),
    "glFramebufferRenderbuffer": (_V, _u, _u, _u, _u),
    "glCheckFramebufferStatus": (_u, _u),
    "glClipControl": (_V, _u, _u),
    "glClearTexSubImage": (_V, _u, _i, _i, _i, _i, _i, _i, _i, _u, _u, _p),
}


class RawGLError(RenderError):
    pass


def _library(soname: str, short: str):
    """ctypes.CDLL of `soname`, else of what find_library finds for `short`, else None."""
    try:
        return ctypes.CDLL(soname)
    except OSError:
        found = ctypes.util.find_library(short)
        return ctypes.CDLL(found) if found else None


def _egl_loader():
    egl = _library("libEGL.so.1", "EGL")
    if egl is None:
        return None, None
    current = egl.eglGetCurrentContext
    current.restype = ctypes.c_void_p
    get = egl.eglGetProcAddress
    get.restype = ctypes.c_void_p
    get.argtypes = [ctypes.c_char_p]
    return get, bool(current())


def _glx_loader():
    glx = _library("libGL.so.1", "GL")
    if glx is None or not hasattr(glx, "glXGetCurrentContext"):
        return None, None
    current = glx.glXGetCurrentContext
    current.restype = ctypes.c_void_p
    get = glx.glXGetProcAddressARB
    get.restype = ctypes.c_void_p
    get.argtypes = [ctypes.c_char_p]
    return get, bool(current())


def proc_address_loader() -> tuple[object, str]:
    """(get_proc_address, "EGL" | "GLX") of the API whose context is current on this thread;
    EGL when none is (the renderer makes its EGL context current before any raw call)."""
    egl_get, egl_current = _egl_loader()
    if egl_current:
        return egl_get, "EGL"
    glx_get, glx_current = _glx_loader()
    if glx_current:
        return glx_get, "GLX"
    if egl_get is None:
        raise RawGLError("libEGL not found: install libegl1 (Debian/Ubuntu) or your GPU "
                         "vendor's EGL driver")
    return egl_get, "EGL"


class RawGL:
    """Raw GL entry points for the context that is current when it is made (the renderer's
    EGL context, or a window's GLX context: see `proc_address_loader`).  Holds function
    pointers only, no GL objects; `api` says where they came from."""

    def __init__(self):
        get, self.api = proc_address_loader()
        for fname, (restype, *args) in _SIGNATURES.items():
            address = get(fname.encode())
            if not address:
                raise RawGLError(f"{self.api}: no {fname} for the current context")
            proto = ctypes.CFUNCTYPE(restype, *args)
            setattr(self, fname, proto(address))

    # -- queries -----------------------------------------------------------------------------
    def get_int(self, pname: int) -> int:
        out = (ctypes.c_int * 4)()
        self.glGetIntegerv(pname, out)
        return int(out[0])

    def check(self, what: str) -> None:
        err = self.glGetError()
        if err:
            raise RawGLError(f"GL error 0x{err:04X} after {what}")
