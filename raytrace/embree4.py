"""The one raw-Embree place: the Embree 4 library that the embreex wheel ships
(site-packages/embreex.libs/libembree4-*.so.4, with its libtbb), bound with ctypes.

embreex traces one ray per call (`rtcIntersect1`, `rtcOccluded1`); Embree's packet queries
(`rtcIntersect8`/`rtcOccluded8`, else 16 or 4: the first of `PACKET_WIDTHS` this CPU runs
natively) are in the same library, unbound.  This module loads that library, declares the few entry points the packet path
needs, and builds a scene the way embreex builds its own (`EmbreeScene(robust=True)` and
`TriangleMesh`: one triangle geometry, float3 vertices with a 16-byte stride, uint3 indices,
RTC_SCENE_FLAG_ROBUST, the default build quality), so that both answer the same rays alike.
The packets themselves are driven by `raytrace.packetkernels` (numba), which receives the
ctypes function objects and the scene's address from here; nothing else in the project imports
ctypes outside shadowvol/raster (tests/test_architecture.py names this file as the witness's
one exception: the witness may not import the raster, and Embree is its library, not GL's).

No compiler at install time: the library is embreex's own, loaded at run time; where it is
missing (an embreex without `embreex.libs`, another platform) `library()` is None and the
backends fall back to embreex's single rays (`raytrace.backends.make_backend`).
"""

from __future__ import annotations

import ctypes
import glob
import os
import threading

import numpy as np

# Embree 4's enums (include/embree4/rtcore_*.h)
_GEOMETRY_TYPE_TRIANGLE = 0
_BUFFER_TYPE_INDEX, _BUFFER_TYPE_VERTEX = 0, 1
_FORMAT_UINT3, _FORMAT_FLOAT3 = 0x5003, 0x9003
_SCENE_FLAG_ROBUST = 1 << 2
_NATIVE_RAY = {4: 32, 8: 33, 16: 34}   # RTC_DEVICE_PROPERTY_NATIVE_RAY{4,8,16}_SUPPORTED
# The packet widths in order of preference, the first the CPU runs natively: 8 before 16.  On
# this project's AVX-512 machine, with the robust scene the masks need, rtcIntersect8 and
# rtcOccluded8 cost 57 ns a ray against rtcIntersect16's 71 (100k triangles, primary and
# shadow rays alike; 71 against 84 at 1M; docs/speed.md).
PACKET_WIDTHS = (8, 16, 4)

_lock = threading.Lock()
_loaded: list = []   # [Library or None], once
_why: list = []      # [why it is None, or ""]


class Library:
    """The loaded library: `intersect` and `occluded`, the ctypes functions
    rtcIntersectN(valid, scene, rayhit, args) and rtcOccludedN(valid, scene, ray, args) of the
    packet width `width` (pointers passed as 64-bit integers, which numba can hand over), and
    the scene calls `Scene` uses."""

    def __init__(self, lib: ctypes.CDLL):
        p, u, size = ctypes.c_void_p, ctypes.c_uint, ctypes.c_size_t

        def fn(name, restype, *argtypes):
            f = getattr(lib, name)
            f.restype, f.argtypes = restype, list(argtypes)
            return f

        self.new_device = fn("rtcNewDevice", p, ctypes.c_char_p)
        self.device_property = fn("rtcGetDeviceProperty", ctypes.c_ssize_t, p, ctypes.c_int)
        self.release_device = fn("rtcReleaseDevice", None, p)
        self.new_scene = fn("rtcNewScene", p, p)
        self.scene_flags = fn("rtcSetSceneFlags", None, p, ctypes.c_int)
        self.new_geometry = fn("rtcNewGeometry", p, p, ctypes.c_int)
        self.new_buffer = fn("rtcSetNewGeometryBuffer", p, p, ctypes.c_int, u, ctypes.c_int,
                             size, size)
        self.commit_geometry = fn("rtcCommitGeometry", None, p)
        self.attach = fn("rtcAttachGeometry", u, p, p)
        self.release_geometry = fn("rtcReleaseGeometry", None, p)
        self.commit_scene = fn("rtcCommitScene", None, p)
        self.release_scene = fn("rtcReleaseScene", None, p)
        self.device = self.new_device(None)
        if not self.device:
            raise OSError("rtcNewDevice failed")
        self.width = next((w for w in PACKET_WIDTHS
                           if self.device_property(self.device, _NATIVE_RAY[w]) == 1), 4)
        word = ctypes.c_uint64
        self.intersect = fn(f"rtcIntersect{self.width}", None, word, word, word, word)
        self.occluded = fn(f"rtcOccluded{self.width}", None, word, word, word, word)


def embreex_module():
    """The embreex package, or None where it is not installed."""
    try:
        import embreex
    except ImportError:
        return None
    return embreex


def library_path() -> str | None:
    """The path of the Embree 4 library inside the embreex wheel, or None."""
    embreex = embreex_module()
    if embreex is None:
        return None
    here = os.path.dirname(os.path.dirname(os.path.abspath(embreex.__file__)))
    found = sorted(glob.glob(os.path.join(here, "embreex.libs", "libembree4*.so*")))
    return found[0] if found else None


def library() -> Library | None:
    """The library, loaded once per process; None where the embreex wheel ships none or it
    does not load (then the reason is `why_not()`)."""
    with _lock:
        if not _loaded:
            path = library_path()
            try:
                _loaded.append(Library(ctypes.CDLL(path)) if path else None)
                _why.append("" if path else "the embreex wheel ships no Embree 4 library")
            except (OSError, AttributeError) as exc:
                _loaded.append(None)
                _why.append(f"Embree 4 library {path}: {exc}")
        return _loaded[0]


def why_not() -> str:
    """Why `library()` is None ("" when it is not)."""
    library()
    return _why[0]


class Scene:
    """The triangles (vertices (N, 3), faces (M, 3)) as one committed Embree scene of
    `Library`'s device, built as embreex builds its own; `handle` is its address (int)."""

    def __init__(self, lib: Library, vertices: np.ndarray, faces: np.ndarray):
        self._lib = lib
        self.handle = lib.new_scene(lib.device)
        lib.scene_flags(self.handle, _SCENE_FLAG_ROBUST)
        geometry = lib.new_geometry(lib.device, _GEOMETRY_TYPE_TRIANGLE)
        nv, nf = len(vertices), len(faces)
        if nv and nf:
            _fill(lib.new_buffer(geometry, _BUFFER_TYPE_VERTEX, 0, _FORMAT_FLOAT3, 16, nv),
                  ctypes.c_float, (nv, 4))[:, :3] = np.asarray(vertices, np.float32)
            _fill(lib.new_buffer(geometry, _BUFFER_TYPE_INDEX, 0, _FORMAT_UINT3, 12, nf),
                  ctypes.c_uint, (nf, 3))[:] = np.asarray(faces, np.uint32)
            lib.commit_geometry(geometry)
            lib.attach(self.handle, geometry)
        lib.release_geometry(geometry)
        lib.commit_scene(self.handle)

    def __del__(self):
        handle, self.handle = getattr(self, "handle", None), None
        if handle:
            self._lib.release_scene(handle)


def _fill(address: int, ctype, shape: tuple[int, int]) -> np.ndarray:
    """A numpy view (shape) of the Embree-owned buffer at `address`."""
    count = shape[0] * shape[1]
    return np.ctypeslib.as_array((ctype * count).from_address(address)).reshape(shape)
