"""The EGL devices of this machine, by libEGL's device queries (ctypes, no context made).

glcontext's EGL backend takes a `device_index` into eglQueryDevicesEXT's list
(`shadowvol.raster.platform.context.create_context(device=)`), and the NVIDIA driver's
EGL_NV_device_cuda extension tells which CUDA device an EGL device is; `shadowvol.batch.egl`
chooses among them.  No GL is loaded here.
"""

from __future__ import annotations

import ctypes
import ctypes.util
from dataclasses import dataclass

# EGL enums (EGL_EXT_device_query, EGL_EXT_device_drm, EGL_EXT_device_query_name,
# EGL_NV_device_cuda)
EGL_EXTENSIONS = 0x3055
EGL_DRM_DEVICE_FILE_EXT = 0x3233
EGL_RENDERER_EXT = 0x335F
EGL_CUDA_DEVICE_NV = 0x323A
MAX_DEVICES = 64


@dataclass(frozen=True)
class Device:
    """One EGL device: its index (what `create_context(device=)` takes), the extensions it
    names, its DRM node and renderer name where EGL says them, its CUDA device where
    EGL_NV_device_cuda says it."""

    index: int
    extensions: tuple[str, ...]
    drm_file: str | None
    renderer: str | None
    cuda_device: int | None

    def describe(self) -> str:
        name = self.renderer or self.drm_file or (
            "Mesa software" if "EGL_MESA_device_software" in self.extensions else "unnamed")
        cuda = "" if self.cuda_device is None else f", CUDA device {self.cuda_device}"
        return f"{self.index} ({name}{cuda})"


def devices() -> list[Device]:
    """The EGL devices of this machine, in eglQueryDevicesEXT's order (empty when libEGL or its
    device extensions are missing)."""
    name = ctypes.util.find_library("EGL")
    if name is None:
        return []
    try:
        lib = ctypes.CDLL(name)
    except OSError:
        return []
    proc = lib.eglGetProcAddress
    proc.restype, proc.argtypes = ctypes.c_void_p, [ctypes.c_char_p]

    def function(fname: str, restype, *argtypes):
        address = proc(fname.encode())
        return ctypes.CFUNCTYPE(restype, *argtypes)(address) if address else None

    query_devices = function("eglQueryDevicesEXT", ctypes.c_uint, ctypes.c_int,
                             ctypes.POINTER(ctypes.c_void_p), ctypes.POINTER(ctypes.c_int))
    query_string = function("eglQueryDeviceStringEXT", ctypes.c_char_p, ctypes.c_void_p,
                            ctypes.c_int)
    query_attrib = function("eglQueryDeviceAttribEXT", ctypes.c_uint, ctypes.c_void_p,
                            ctypes.c_int, ctypes.POINTER(ctypes.c_ssize_t))
    if query_devices is None or query_string is None:
        return []
    handles = (ctypes.c_void_p * MAX_DEVICES)()
    count = ctypes.c_int(0)
    if not query_devices(MAX_DEVICES, handles, ctypes.byref(count)):
        return []
    found = []
    for i in range(count.value):
        handle = handles[i]
        extensions = tuple((query_string(handle, EGL_EXTENSIONS) or b"").decode().split())
        drm = query_string(handle, EGL_DRM_DEVICE_FILE_EXT) \
            if "EGL_EXT_device_drm" in extensions else None
        renderer = query_string(handle, EGL_RENDERER_EXT) \
            if "EGL_EXT_device_query_name" in extensions else None
        cuda = None
        if "EGL_NV_device_cuda" in extensions and query_attrib is not None:
            value = ctypes.c_ssize_t(-1)
            if query_attrib(handle, EGL_CUDA_DEVICE_NV, ctypes.byref(value)):
                cuda = int(value.value)
        found.append(Device(i, extensions, drm.decode() if drm else None,
                            renderer.decode() if renderer else None, cuda))
    return found
