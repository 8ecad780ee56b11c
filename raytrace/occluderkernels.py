"""`occluders.objects`' per-triangle and per-member arrays in numba (the `fast` extra), one
pass over the triangles and one over the clusters' members where numpy makes ~20 over
arrays of the bunny's 70k triangles (22 -> 3 ms; the frame's objects 34 -> 25 ms): the same
floats, bit for bit, as numpy's path (each product and sum in numpy's order; minima and
maxima by numpy's rule, so -0.0 and 0.0 come out as numpy gives them).
tests/raytrace/test_occluders.py holds the two to the same bytes.
"""

from __future__ import annotations

import numpy as np

from .packetkernels import _jit


@_jit(inline="always")
def _least(a, b):
    """np.minimum(a, b) of two floats: a where a < b or a is NaN, else b."""
    return a if a < b or a != a else b


@_jit(inline="always")
def _most(a, b):
    """np.maximum(a, b) of two floats: a where a > b or a is NaN, else b."""
    return a if a > b or a != a else b


@_jit()
def normals(corners):
    """(unit normals (M, 3) by winding, (b - a) x (c - a) over its length, 0 where that is 0;
    the lengths (M,)) of triangles corners (M, 3, 3): np.cross, np.linalg.norm's root of
    the squares summed in order, and the quotient."""
    m = corners.shape[0]
    out, length = np.zeros((m, 3)), np.empty(m)
    for t in range(m):
        u0, u1, u2 = (corners[t, 1, 0] - corners[t, 0, 0], corners[t, 1, 1] - corners[t, 0, 1],
                      corners[t, 1, 2] - corners[t, 0, 2])
        v0, v1, v2 = (corners[t, 2, 0] - corners[t, 0, 0], corners[t, 2, 1] - corners[t, 0, 1],
                      corners[t, 2, 2] - corners[t, 0, 2])
        c0, c1, c2 = u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0
        size = np.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
        length[t] = size
        if size > 0:
            out[t, 0], out[t, 1], out[t, 2] = c0 / size, c1 / size, c2 / size
    return out, length


@_jit()
def fields(corners, normal, shell, kind, welded, members):
    """`occluders.objects`' arrays of triangles corners (M, 3, 3) with unit normals, shells
    (M, 3), kinds (M,) and welded corners (M, 3), clustered as members (C, K) (-1 pads, read
    as triangle 0): (tri_lo, tri_hi (M, 3), scale (M,), offset (M,) normal . first corner,
    packed (C, K, 16), the clusters' boxes lo, hi (C, 3) (their members' boxes', pads left
    out), kinds (C, K), member_ids (C, K, 3))."""
    m, (c_count, width) = corners.shape[0], members.shape
    tri_lo, tri_hi = np.empty((m, 3)), np.empty((m, 3))
    scale, offset = np.empty(m), np.empty(m)
    for t in range(m):
        most = 0.0
        for a in range(3):
            low = _least(_least(corners[t, 0, a], corners[t, 1, a]), corners[t, 2, a])
            high = _most(_most(corners[t, 0, a], corners[t, 1, a]), corners[t, 2, a])
            tri_lo[t, a], tri_hi[t, a] = low, high
            far = _most(abs(low), abs(high))
            most = far if a == 0 else _most(most, far)
        scale[t] = most
        offset[t] = normal[t, 0] * corners[t, 0, 0] + normal[t, 1] * corners[t, 0, 1] + \
            normal[t, 2] * corners[t, 0, 2]
    packed = np.empty((c_count, width, 16))
    lo, hi = np.full((c_count, 3), np.inf), np.full((c_count, 3), -np.inf)
    kinds, ids = np.empty((c_count, width), np.int64), np.empty((c_count, width, 3), np.int64)
    for c in range(c_count):
        for k in range(width):
            t = max(members[c, k], 0)
            for a in range(3):
                packed[c, k, a], packed[c, k, 3 + a] = tri_lo[t, a], tri_hi[t, a]
                packed[c, k, 6 + a], packed[c, k, 9 + a] = normal[t, a], shell[t, a]
                packed[c, k, 12 + a] = corners[t, 0, a]
                ids[c, k, a] = welded[t, a]
                if members[c, k] >= 0:
                    lo[c, a], hi[c, a] = _least(lo[c, a], tri_lo[t, a]), _most(hi[c, a],
                                                                              tri_hi[t, a])
            packed[c, k, 15] = scale[t]
            kinds[c, k] = kind[t]
    return tri_lo, tri_hi, scale, offset, packed, lo, hi, kinds, ids
