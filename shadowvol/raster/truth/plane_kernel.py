"""`plane_depth.plane_depths`' per-pixel step and `truth_pass.surface_outputs` compiled with
numba (the `fast` extra), the same values as their numpy forms (the depth's float64 operations in
the same order); each `None` where numba is missing.

Per pixel i (flat index pixel[i], triangle row which[i]): n . v summed from 0 as
((0 + t0) + t1) + t2 with t_k = (row[k, y] + col[k, x]) * n[w, k], s = num[w] / (n . v) and, where
s is finite and positive, out[pixel[i]] = float32(s).  numba's default keeps IEEE order (no
fast-math, no fused multiply-add) and `error_model="numpy"` divides by zero as numpy does.
"""

from __future__ import annotations

import math

try:
    import numba
except ImportError:    # the `fast` extra not installed: plane_depth's numpy path
    numba = None


def _depths(pixel, which, width, row, col, n, num, out):
    for i in range(pixel.shape[0]):
        p = pixel[i]
        y = p // width
        x = p - y * width
        w = which[i]
        n_dot_v = 0.0
        for k in range(3):
            term = row[k, y]
            term += col[k, x]
            term *= n[w, k]
            n_dot_v += term
        s = num[w] / n_dot_v
        if s > 0 and s < math.inf:   # finite and positive (nan fails both)
            out[p] = s


depths = None
if numba is not None:
    try:
        depths = numba.njit(cache=True, nogil=True, error_model="numpy")(_depths)
    except RuntimeError:   # no writable cache directory
        depths = numba.njit(nogil=True, error_model="numpy")(_depths)


def _surface(triangle, front, normals, objects, normal, object_id, want_normal, want_id):
    """`truth_pass.surface_outputs` in one pass over the pixels (flat arrays): each covered
    pixel's triangle's float32 normal, negated where its back face is seen, and its object's
    index + 1 as uint16 (wrapping as numpy's astype does); 0 where nothing is drawn."""
    for i in range(triangle.shape[0]):
        t = triangle[i]
        if want_normal:
            for k in range(3):
                if t < 0:
                    normal[i, k] = 0.0
                elif front[i]:
                    normal[i, k] = normals[t, k]
                else:
                    normal[i, k] = -normals[t, k]
        if want_id:
            object_id[i] = 0 if t < 0 else objects[t] + 1


surface = None
if numba is not None:
    try:
        surface = numba.njit(cache=True, nogil=True)(_surface)
    except RuntimeError:   # no writable cache directory
        surface = numba.njit(nogil=True)(_surface)
