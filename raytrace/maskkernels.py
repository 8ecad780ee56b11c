"""The masks' per-pixel arithmetic in numba (the `fast` extra), for the packet path: what
`raytrace.masks` computes in numpy between its ray casts, in one pass over a tile's pixels
each, with the GIL released (the tiles run on the masks' thread pool).

* `primary_hits`: the tile's primary rays, made here from the `RayGrid`s' factors and traced in
  Embree's packets (`raytrace.packetkernels`), then each covered pixel's hit as
  `masks._primary_hits` makes it (the float64 point on the triangle's plane, its float32
  rounding, the side, the height bound);
* `point_segments` and `directional_segments`: the shadow rays of the hits toward one light
  and the near pieces a long lift skips, as `masks._point_segments` and
  `masks._directional_segments` make them;
* `box_candidates`: for `raytrace.groundtruth`'s casters, the blocked segments that may meet
  each object's padded box, as `groundtruth._meets_box` tests them (np.fmin and np.fmax's NaN
  rules), without numpy's temporaries (tests/raytrace/test_groundtruth.py compares them);
* `pixel_outputs`: `groundtruth`'s depth, distance, normal and object_id of a tile's hits in
  one pass, without gathering the tile's directions (the same test compares the bytes).

Each is the numpy code's own arithmetic, operation for operation and in the same order, in the
same precision (float32 where numpy works in float32, float64 where it works in float64; dot
products summed x, y, z left to right as `masks._dot` sums them), with numpy's NaN rules for
`maximum` and `minimum`: the same bits.  numba compiles without fast-math, so nothing is fused
or reordered.  tests/raytrace/test_mask_kernels.py compares every output array with numpy's,
bit for bit, and tests/raytrace/test_packets.py the masks of both paths.
"""

from __future__ import annotations

import numpy as np

from .packetkernels import DIR, INVALID, NO_BOUND, ORG, PRIM_ID, ROWS, VALID, _jit, reset_lane
from .tolerances import FLOAT32_EPS, LIGHT_ERROR_ULPS, LIFT_HEIGHTS, SURFACE_ERROR_ULPS

_HEIGHT = SURFACE_ERROR_ULPS * FLOAT32_EPS   # `tolerances.shadow_height`'s factor
_MARGIN = LIGHT_ERROR_ULPS * FLOAT32_EPS     # `tolerances.light_margin`'s factor


@_jit()
def _max(a, b):
    """np.maximum of two floats: NaN if either is."""
    return a if a > b or a != a else b


@_jit()
def _min(a, b):
    """np.minimum of two floats: NaN if either is."""
    return a if a < b or a != a else b


# A packet's pixels: a block BLOCK_ROWS rows tall and width / BLOCK_ROWS wide (4 x 2 in packets
# of 8), not a run of one row: nearer rays, fewer BVH nodes a packet visits (on the 1M scene
# 67 ns a ray against 72; the answers are each ray's own, as test_packets holds them).
BLOCK_ROWS = 2


@_jit()
def _trace_blocks(fn, scene, width, block_rows, y0, y1, row32, col32, eye32, near32, tri):
    """tri (R*W,) int64, row-major: the primID of each pixel of rows y0..y1-1, -1 for none:
    the ray eye32 + near32·d, d = row32[:, y] + col32[:, x] (float32), unbounded (tfar
    NO_BOUND), its lanes set by `packetkernels.reset_lane`, in packets of `width` pixels, blocks of
    block_rows rows (fewer at the tile's foot and right edge)."""
    W = col32.shape[1]
    bh = min(block_rows, width)
    bw = width // bh
    buf = np.empty(ROWS * width + 16, np.float32)
    start = ((64 - buf.ctypes.data % 64) % 64) // 4   # 64-byte alignment (RTC_ALIGN(64))
    f = buf[start:start + ROWS * width]
    u = f.view(np.uint32)
    valid = f[VALID * width:(VALID + 1) * width].view(np.int32)
    pixel = np.empty(width, np.int64)
    for by in range(y0, y1, bh):
        for bx in range(0, W, bw):
            k = np.int64(0)      # not a literal: numba would compile reset_lane for it too
            for y in range(by, min(by + bh, y1)):
                for x in range(bx, min(bx + bw, W)):
                    pixel[k] = (y - y0) * W + x
                    for a in range(3):
                        d = row32[a, y] + col32[a, x]
                        f[(ORG + a) * width + k] = eye32[a] + near32 * d
                        f[(DIR + a) * width + k] = d
                    reset_lane(f, u, width, k, NO_BOUND)
                    k += 1
            for lane in range(width):
                valid[lane] = -1 if lane < k else 0
            fn(valid.ctypes.data, scene, f.ctypes.data, 0)
            for lane in range(k):
                prim = u[PRIM_ID * width + lane]
                tri[pixel[lane]] = -1 if prim == INVALID else np.int64(prim)


@_jit()
def primary_hits(fn, scene, width, block_rows, y0, y1, row32, col32, eye32, near32, row64, col64, eye64,
                 normals_t, plane_d, weight, fragile):
    """`masks._primary_hits` of rows y0..y1-1 on the packet queries fn (rtcIntersectN) of the
    committed `scene` (its address), in packets of blocks `block_rows` tall: (tri (R*W,) int64, -1 uncovered; index (h,) int64; then
    the hits' point (3, h) float32, normal (3, h), side, side_d, height, k (h,) int64,
    fragile (h,) bool, depth s, point64 (3, h): `masks._Hits`' fields)."""
    W = col32.shape[1]
    tri = np.empty((y1 - y0) * W, np.int64)
    _trace_blocks(fn, scene, width, block_rows, y0, y1, row32, col32, eye32, near32, tri)
    h = 0
    for i in range(tri.shape[0]):
        h += tri[i] >= 0
    index = np.empty(h, np.int64)
    point = np.empty((3, h), np.float32)
    normal, point64 = np.empty((3, h)), np.empty((3, h))
    side, side_d, height, depth = np.empty(h), np.empty(h), np.empty(h), np.empty(h)
    ks, frag = np.empty(h, np.int64), np.empty(h, np.bool_)
    j = 0
    for i in range(tri.shape[0]):
        k = tri[i]
        if k < 0:
            continue
        y, x = y0 + i // W, i % W
        v0, v1, v2 = row64[0, y] + col64[0, x], row64[1, y] + col64[1, x], \
            row64[2, y] + col64[2, x]
        n0, n1, n2 = normals_t[0, k], normals_t[1, k], normals_t[2, k]
        n_dot_v = n0 * v0 + n1 * v1 + n2 * v2
        d = plane_d[k]
        s = (d - (eye64[0] * n0 + eye64[1] * n1 + eye64[2] * n2)) / n_dot_v
        p0, p1, p2 = eye64[0] + s * v0, eye64[1] + s * v1, eye64[2] + s * v2
        sd = -1.0 if n_dot_v > 0 else 1.0
        w = weight[k] + (abs(n0) * abs(p0) + abs(n1) * abs(p1) + abs(n2) * abs(p2))
        index[j], ks[j], frag[j], depth[j] = i, k, fragile[k], s
        point64[0, j], point64[1, j], point64[2, j] = p0, p1, p2
        point[0, j], point[1, j], point[2, j] = np.float32(p0), np.float32(p1), np.float32(p2)
        normal[0, j], normal[1, j], normal[2, j] = n0, n1, n2
        side[j], side_d[j], height[j] = sd, sd * d, _HEIGHT * _max(w, 1e-30)
        j += 1
    return tri, index, point, normal, side, side_d, height, ks, frag, depth, point64


@_jit()
def _round_down32(x):
    """`masks._round_down32` of one float64."""
    y = np.float32(x)
    return np.nextafter(y, np.float32(0)) if np.float64(y) > x else y


@_jit()
def point_segments(position, own, through, spot, axis, cos_cutoff, point, normal, side,
                   side_d, height):
    """`masks._point_segments` toward the point light at position (3,) float64 (own: the
    largest |coordinate| of it; through: `_LocalLight.through`); spot: a spot light, of unit
    axis (3,) float64 and cos_cutoff (float32, as numpy rounds the Python float against the
    float32 lengths).  Returns facing (h,) bool, rays (r,) int64, start (3, r) float32,
    l (3, r) float32, gap (r,) float32, and the near pieces' hits (q,) int64 and tmax (q,)."""
    h = point.shape[1]
    facing = np.zeros(h, np.bool_)
    rays, near_k = np.empty(h, np.int64), np.empty(h, np.int64)
    start, l = np.empty((3, h), np.float32), np.empty((3, h), np.float32)
    gap, near_t = np.empty(h, np.float32), np.empty(h)
    L0, L1, L2 = np.float32(position[0]), np.float32(position[1]), np.float32(position[2])
    r = q = 0
    for i in range(h):
        n_dot_l = side[i] * (position[0] * normal[0, i] + position[1] * normal[1, i] +
                             position[2] * normal[2, i]) - side_d[i]
        if not n_dot_l > 0:
            continue
        s0, s1, s2 = point[0, i], point[1, i], point[2, i]
        l0, l1, l2 = L0 - s0, L1 - s1, L2 - s2
        length32 = np.float32(np.sqrt(l0 * l0 + l1 * l1 + l2 * l2))
        if spot and not (-(axis[0] * np.float64(l0) + axis[1] * np.float64(l1) +
                           axis[2] * np.float64(l2)) >= cos_cutoff * length32):
            continue
        facing[i] = True
        near = height[i] / n_dot_l
        length = np.float64(length32)
        end = 1.0 - _MARGIN * _max(own + length + through, 1e-30) / length
        if near * length > LIFT_HEIGHTS * height[i]:
            near_k[q], near_t[q] = i, _min(near, end)
            q += 1
        g = end - near
        if g > 0:
            n32 = np.float32(near)
            start[0, r], start[1, r], start[2, r] = s0 + n32 * l0, s1 + n32 * l1, s2 + n32 * l2
            l[0, r], l[1, r], l[2, r] = l0, l1, l2
            gap[r], rays[r] = _round_down32(g), i
            r += 1
    return (facing, rays[:r], start[:, :r], l[:, :r], gap[:r], near_k[:q], near_t[:q])


@_jit()
def directional_segments(toward, reach, point, normal, side, height):
    """`masks._directional_segments` toward the unit direction toward (3,) float64 (minus the
    light's direction), within reach: facing (h,) bool, rays (r,) int64, start (3, r)
    float32, and the near pieces' hits (q,) int64 and tmax (q,)."""
    h = point.shape[1]
    facing = np.zeros(h, np.bool_)
    rays, near_k = np.empty(h, np.int64), np.empty(h, np.int64)
    start, near_t = np.empty((3, h), np.float32), np.empty(h)
    t0, t1, t2 = np.float32(toward[0]), np.float32(toward[1]), np.float32(toward[2])
    r = q = 0
    for i in range(h):
        n_dot_l = side[i] * (toward[0] * normal[0, i] + toward[1] * normal[1, i] +
                             toward[2] * normal[2, i])
        if not n_dot_l > 0:
            continue
        facing[i] = True
        near = height[i] / n_dot_l
        if near < reach:
            n32 = np.float32(near)
            start[0, r] = point[0, i] + n32 * t0
            start[1, r] = point[1, i] + n32 * t1
            start[2, r] = point[2, i] + n32 * t2
            rays[r] = i
            r += 1
        if near > LIFT_HEIGHTS * height[i]:
            near_k[q], near_t[q] = i, _min(near, reach)
            q += 1
    return facing, rays[:r], start[:, :r], near_k[:q], near_t[:q]


@_jit()
def through_light(normals_t, plane_d, weight, position):
    """`tolerances.through_light` in one pass: normals_t (3, M), plane_d (M,), weight (M,),
    the light's position (3,), all float64."""
    best, found = 0.0, False
    a0, a1, a2 = abs(position[0]), abs(position[1]), abs(position[2])
    for i in range(plane_d.shape[0]):
        n0, n1, n2 = normals_t[0, i], normals_t[1, i], normals_t[2, i]
        w = weight[i] + (abs(n0) * a0 + abs(n1) * a1 + abs(n2) * a2)
        if abs((n0 * position[0] + n1 * position[1] + n2 * position[2]) - plane_d[i]) <= \
                _HEIGHT * _max(w, 1e-30):
            best = w if not found else _max(best, w)
            found = True
    return best


@_jit()
def _fmin(a, b):
    """np.fmin of two floats: the other where one is NaN."""
    if a != a:
        return b
    return a if a < b or b != b else b


@_jit()
def _fmax(a, b):
    """np.fmax of two floats: the other where one is NaN."""
    if a != a:
        return b
    return a if a > b or b != b else b


@_jit()
def _slab(start, inverse, lo, hi, i, j, a):
    """Where segment i enters and leaves box j's slab along axis a (NaN: inside it, 0 · inf)."""
    t1 = (lo[j, a] - start[a, i]) * inverse[a, i]
    t2 = (hi[j, a] - start[a, i]) * inverse[a, i]
    return _fmin(t1, t2), _fmax(t1, t2)


@_jit()
def _meets(start, inverse, end, lo, hi, i, j):
    """`groundtruth._meets_box` of segment i and box j: the same slab arithmetic, NaN rules."""
    l0, u0 = _slab(start, inverse, lo, hi, i, j, 0)
    l1, u1 = _slab(start, inverse, lo, hi, i, j, 1)
    l2, u2 = _slab(start, inverse, lo, hi, i, j, 2)
    t_in = _fmax(_fmax(l0, l1), _fmax(l2, 0.0))
    t_out = _fmin(_fmin(u0, u1), _fmin(u2, end[i]))
    return t_in <= t_out


@_jit()
def box_candidates(start, inverse, end, lo, hi, casts, own_object):
    """The segments (start, inverse (3, b) float64, end (b,) float64) that may meet each
    casting object j (casts (n,) bool): those meeting its padded box [lo[j], hi[j]] ((n, 3)
    float64, as `groundtruth._meets_box` tests it) or leaving it (own_object (b,) == j).
    Returns first (n + 1,) int64 and k (first[n],) int64: object j's segments, ascending, are
    k[first[j]:first[j + 1]].  Each (segment, box) pair is tested once, its answer kept as a
    bit (b x ceil(n / 64) words) until the lists are written."""
    n, b = lo.shape[0], start.shape[1]
    met = np.zeros((b, (n + 63) // 64), np.uint64)
    first = np.zeros(n + 1, np.int64)
    for i in range(b):
        for j in range(n):
            if casts[j] and (own_object[i] == j or _meets(start, inverse, end, lo, hi, i, j)):
                met[i, j >> 6] |= np.uint64(1) << np.uint64(j & 63)
                first[j + 1] += 1
    for j in range(n):
        first[j + 1] += first[j]
    k = np.empty(first[n], np.int64)
    fill = first[:n].copy()
    for i in range(b):
        for j in range(n):
            if (met[i, j >> 6] >> np.uint64(j & 63)) & np.uint64(1):
                k[fill[j]] = i
                fill[j] += 1
    return first, k


@_jit()
def pixel_outputs(first, width, y0, index, row64, col64, depth, tri, side, normals, ids,
                  want, out_depth, out_distance, out_normal, out_object_id):
    """`groundtruth`'s per-pixel outputs of a tile's hits, written at pixel first + index[i]:
    depth (float32 of the eye-space depth), distance (depth · |v|, v = row64[:, y] +
    col64[:, x] the pixel's float64 direction of depth 1, |v|² summed x, y, z left to right
    as numpy sums axis 0), normal (normals[tri] · side) and object_id (ids[tri] + 1), each
    where want[0..3] is True (the others may be empty arrays)."""
    for i in range(index.shape[0]):
        p = first + index[i]
        t = tri[i]
        if want[0]:
            out_depth[p] = np.float32(depth[i])
        if want[1]:
            y, x = y0 + index[i] // width, index[i] % width
            v0 = row64[0, y] + col64[0, x]
            v1 = row64[1, y] + col64[1, x]
            v2 = row64[2, y] + col64[2, x]
            out_distance[p] = np.float32(depth[i] * np.sqrt(v0 * v0 + v1 * v1 + v2 * v2))
        if want[2]:
            for a in range(3):
                out_normal[p, a] = np.float32(normals[t, a] * side[i])
        if want[3]:
            out_object_id[p] = np.uint16(ids[t] + 1)
