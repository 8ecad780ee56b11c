"""Embree's packet queries driven by numba (the optional `fast` extra): rays in packets of the
library's width (8 where the CPU runs it natively, else 16 or 4; `raytrace.embree4`), `nogil`,
over chunks of consecutive rays on numba's threads (`trace(..., parallel=True)`) or on the caller's
(`parallel=False`: the masks' tiles, each on a thread of their own pool).

Consecutive rays make a packet: in the masks that is a run of pixels of one image row (primary
rays) and the shadow rays of consecutive covered pixels, which start close together and head
for the same light: coherent packets, which Embree's hybrid traversal walks together.

Each ray is set exactly as embreex sets its single ray (tnear 0, time 0, mask all ones, flags
0, the ids invalid, tfar the bound or 1e37), so the packet and the single-ray queries ask Embree
the same question; tests/raytrace/test_packets.py holds them to the same answers, bit for bit.
"""

from __future__ import annotations

import numba
import numpy as np

# RTCRayHitN as structure of arrays, in rows of `width` 4-byte words (rtcore_ray.h): the ray's
# org_x, org_y, org_z, tnear, dir_x, dir_y, dir_z, time, tfar, mask, id, flags; then the hit's
# Ng_x, Ng_y, Ng_z, u, v, primID, geomID, instID[1], instPrimID[1]; the valid mask after that.
ORG, TNEAR, DIR, TIME, TFAR, MASK, ID, FLAGS, PRIM_ID, GEOM_ID, VALID = \
    0, 3, 4, 7, 8, 9, 10, 11, 17, 18, 21
ROWS = 22
INVALID = 0xFFFFFFFF
NO_BOUND = np.float32(1e37)   # embreex's own "no bound"
INTERSECT, OCCLUDED = 0, 1
# Rays per chunk of the parallel loop: a chunk reuses one packet buffer.
CHUNK = 4096


def _jit(**flags):
    """njit releasing the GIL, cached on disk where numba finds a writable cache directory
    (numba refuses `cache=True` with a RuntimeError where it finds none)."""
    def wrap(fn):
        try:
            return numba.njit(cache=True, nogil=True, **flags)(fn)
        except RuntimeError:
            return numba.njit(nogil=True, **flags)(fn)
    return wrap


@_jit()
def reset_lane(f, u, width, k, tfar):
    """Lane k of the packet f (its uint32 view u) set as embreex sets its single ray, bar the
    origin and direction: tnear 0, time 0, tfar, mask all ones, id 0, flags 0, the hit's
    primID, geomID and instID invalid."""
    f[TNEAR * width + k] = 0.0
    f[TIME * width + k] = 0.0
    f[TFAR * width + k] = tfar
    u[MASK * width + k] = INVALID
    u[ID * width + k] = 0
    u[FLAGS * width + k] = 0
    u[PRIM_ID * width + k] = INVALID
    u[GEOM_ID * width + k] = INVALID
    u[(GEOM_ID + 1) * width + k] = INVALID


@_jit()
def _rays(query, fn, scene, width, o, d, tfar, lo, hi, tri, t):
    """Trace rays lo..hi-1 in packets of `width` through fn (rtcIntersectN or rtcOccludedN)
    on `scene`: tri[i] = the hit's primID (INTERSECT) or 0 for blocked (OCCLUDED), -1 for
    none; t[i] = Embree's tfar (INTERSECT; inf for none)."""
    buf = np.empty(ROWS * width + 16, np.float32)
    start = ((64 - buf.ctypes.data % 64) % 64) // 4   # 64-byte alignment (RTC_ALIGN(64))
    f = buf[start:start + ROWS * width]
    u = f.view(np.uint32)
    valid = f[VALID * width:(VALID + 1) * width].view(np.int32)
    step_d = 1 if d.shape[0] > 1 else 0
    step_t = 1 if tfar.shape[0] > 1 else 0
    for first in range(lo, hi, width):
        for k in range(width):
            i = first + k
            if i >= hi:
                valid[k] = 0
                continue
            valid[k] = -1
            for a in range(3):
                f[(ORG + a) * width + k] = o[i, a]
                f[(DIR + a) * width + k] = d[i * step_d, a]
            reset_lane(f, u, width, k, tfar[i * step_t])
        fn(valid.ctypes.data, scene, f.ctypes.data, 0)
        for k in range(min(width, hi - first)):
            i = first + k
            if query == OCCLUDED:
                tri[i] = 0 if f[TFAR * width + k] < 0 else -1
            else:
                prim = u[PRIM_ID * width + k]
                tri[i] = -1 if prim == INVALID else np.int64(prim)
                t[i] = np.float32(np.inf) if prim == INVALID else f[TFAR * width + k]


@_jit(parallel=True)
def _parallel(query, fn, scene, width, o, d, tfar, tri, t):
    n = o.shape[0]
    for c in numba.prange((n + CHUNK - 1) // CHUNK):
        _rays(query, fn, scene, width, o, d, tfar, c * CHUNK, min(n, (c + 1) * CHUNK), tri, t)


@_jit()
def _serial(query, fn, scene, width, o, d, tfar, tri, t):
    # np.int64(0), not a literal 0, which numba would compile `_rays` for once more
    _rays(query, fn, scene, width, o, d, tfar, np.int64(0), o.shape[0], tri, t)


def trace(lib, scene: int, query: int, origins: np.ndarray, directions: np.ndarray,
          tfar: np.ndarray, parallel: bool) -> tuple[np.ndarray, np.ndarray]:
    """(tri (n,) int64, t (n,) float32) of the rays (origins (n, 3) float32; directions (n, 3)
    or (1, 3) float32; tfar (n,) or (1,) float32) on the committed `scene` (its address) of
    `lib` (`raytrace.embree4.Library`): query INTERSECT (tri: primID, -1 for a miss; t:
    Embree's tfar, inf for a miss) or OCCLUDED (tri: 0 blocked, -1 clear; t unset)."""
    n = len(origins)
    tri = np.empty(n, np.int64)
    t = np.empty(n if query == INTERSECT else 0, np.float32)
    if n == 0:
        return tri, t
    fn = lib.intersect if query == INTERSECT else lib.occluded
    run = _parallel if parallel and n > CHUNK else _serial
    # C order always (the kernels read a ray's three coordinates together), so that numba
    # compiles each kernel once, not once per layout of its callers' arrays
    origins, directions = np.ascontiguousarray(origins), np.ascontiguousarray(directions)
    run(query, fn, scene, lib.width, origins, directions, tfar, tri, t)
    return tri, t
