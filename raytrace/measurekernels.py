"""`windmeasures._less` in numba (the `fast` extra): `less` measures a row's convex region and
takes away its fan, each signed triangle clipped and measured as it is made, one row at a
time, where numpy's passes carry every piece of every row through arrays (clip, closed rings,
edges).  For a light without a radius (a rect: `exact_soft` winds no `polygon` light's
pixels) and without `direct`; a disk light and `direct` stay in numpy.

numpy's arithmetic in numpy's order: the clip `exactkernels.inside`'s, the shoelace and the
Lambert terms summed from 0.0 edge by edge (`np.bincount`), `np.cross`'s differences, sums of
three left to right (`sum(axis=1)`, `linalg.norm`), and a corner carried into space as
`center + a @ axes - eye` with the matmul's two terms rounded as numpy's BLAS rounds them
(`products`' modes; OpenBLAS with FMA fuses the second onto the first's product; where no
mode matches a probe, `windmeasures` measures in numpy).  So the areas, V, are numpy's bytes.
The irradiance is too where numpy's `arctan2` is the C library's atan2, as numba's is; under
AVX-512 numpy takes SVML's, a last bit apart now and then, and the irradiance moves by a few
units of rounding (tests/raytrace/test_measure_kernels.py holds both).
"""

from __future__ import annotations

import math

import numpy as np
from numba import types
from numba.extending import intrinsic

from .exactkernels import keep_left
from .packetkernels import _jit


@intrinsic
def _fma(typingctx, x, y, z):
    """x * y + z rounded once (LLVM's `llvm.fma`, correctly rounded on every CPU)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        from llvmlite import ir        # numba's own dependency (a missing numba names numba)
        double = ir.DoubleType()
        fn = builder.module.declare_intrinsic("llvm.fma", [double],
                                              ir.FunctionType(double, [double] * 3))
        return builder.call(fn, args)
    return sig, codegen


@_jit(inline="always")
def _two(x, y, u, v, mode):
    """(x, y) @ (u, v) (a column of the light's axes) rounded as `mode` says numpy's matmul
    rounds it: 0 two products summed, 1 the second fused onto the first's product, 2 the
    first onto the second's."""
    if mode == 1:
        return _fma(y, v, x * u)
    if mode == 2:
        return _fma(x, u, y * v)
    return x * u + y * v


@_jit()
def products(a, axes, mode):
    """(n, 3): a (n, 2) @ axes (2, 3) rounded as `mode` says (`_two`): the probe of which
    mode numpy's matmul (its BLAS) takes."""
    out = np.empty((a.shape[0], 3))
    for i in range(a.shape[0]):
        for j in range(3):
            out[i, j] = _two(a[i, 0], a[i, 1], axes[0, j], axes[1, j], mode)
    return out


@_jit(inline="always")
def _space(x, y, frame, mode, eye):
    """The plane point (x, y) seen from eye (3 floats): center + (x, y) @ axes - eye, frame
    the light's center and axes' two rows (9 floats, as `less` makes it)."""
    c0, c1, c2, u0, u1, u2, v0, v1, v2 = frame
    return ((c0 + _two(x, y, u0, v0, mode)) - eye[0], (c1 + _two(x, y, u1, v1, mode)) - eye[1],
            (c2 + _two(x, y, u2, v2, mode)) - eye[2])


@_jit(inline="always")
def _ring(buf, s, c, frame, mode, eye, normal):
    """(|area|, |Lambert's irradiance|) of the closed ring buf[s, :c] (k, 2) seen from eye with
    normal (3 floats each) (`polygons.ring_measures` of one ring).  The light's frame, the
    eye and the normal come as floats, not arrays: numba counts references to an array
    passed to an inlined function with branches, on each call (40 % of this kernel)."""
    area, lam = 0.0, 0.0
    if c == 0:
        return area, lam
    x0 = _space(buf[s, 0, 0], buf[s, 0, 1], frame, mode, eye)
    n0, n1, n2 = normal
    for i in range(c):
        j = i + 1 if i + 1 < c else 0
        area += (buf[s, i, 0] * buf[s, j, 1] - buf[s, i, 1] * buf[s, j, 0]) / 2
        x1 = _space(buf[s, j, 0], buf[s, j, 1], frame, mode, eye)
        c0 = x0[1] * x1[2] - x0[2] * x1[1]
        c1 = x0[2] * x1[0] - x0[0] * x1[2]
        c2 = x0[0] * x1[1] - x0[1] * x1[0]
        sine = math.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
        if sine > 0:
            theta = math.atan2(sine, x0[0] * x1[0] + x0[1] * x1[1] + x0[2] * x1[2])
            lam += 0.5 * theta * (c0 * n0 + c1 * n1 + c2 * n2) / sine
        else:
            lam += 0.0
        x0 = x1
    return abs(area), abs(lam)


@_jit(inline="always")
def _clip(poly, many, l, r, buf, s, c, d):
    """buf[s, :c] clipped by each edge of the convex counter-clockwise polygon poly[l, r,
    :many[l, r]] (`exactkernels.inside` of one row), buf's two sides in turn, through the
    scratch d: (the side holding the corners, their count, whether buf and d had room for
    each edge's 2 c corners, the most a clip of c corners can make whatever the rounding;
    where not, nothing is clipped from there on).  It grows no scratch itself: numba counts
    references to an array a loop may replace, on every pass (docs/speed.md, "Reference
    counts")."""
    m, fits = many[l, r], True
    for e in range(m):
        fits &= (2 * c <= buf.shape[1]) & (c <= d.shape[0])
        c = c if fits else 0
        f = e + 1 if e + 1 < m else 0
        s0, s1 = poly[l, r, e, 0], poly[l, r, e, 1]
        c = keep_left(buf, s, c, s0, s1, poly[l, r, f, 0] - s0, poly[l, r, f, 1] - s1, d)
        s = 1 - s
    return s, c, fits


@_jit()
def less(region, size, polys, counts, edges, start, owner, eye, normal, center, axes, mode,
         room=2):
    """`windmeasures._less` of a polygon light: (area (r,), irradiance (r,)) of the convex
    counter-clockwise regions region (r, k, 2), size (r,) less the unions bounded by the
    chains edges[start[o]:start[o + 1]] (e, 2, 2) of o = owner[r]: the fan of signed triangles
    from the light's centre over each chain edge, clipped by each clipper polys[l, r], counts
    [l, r] ((L, r, m, 2), (L, r): count 0 none) in turn; seen from eye (r, 3) with normals
    (r, 3), the light's plane through center (3,) with axes (2, 3), carried into space as
    `mode` says numpy's matmul rounds (`products`).  The clips go through scratch of `room`
    times the corners a convex clip can make (3 and every clipper's edges, or the region's);
    the rows whose clips find no room there (rounding can make a corner more at each edge)
    are measured again with four times as much (`_rows`)."""
    n = region.shape[0]
    area, irr = np.empty(n), np.empty(n)
    width = room * max(3 + polys.shape[0] * polys.shape[2], region.shape[1])
    frame = (center[0], center[1], center[2], axes[0, 0], axes[0, 1], axes[0, 2], axes[1, 0],
             axes[1, 1], axes[1, 2])
    rows = np.arange(n)
    while rows.shape[0] > 0:
        rows = _rows(rows, width, area, irr, region, size, polys, counts, edges, start, owner,
                     eye, normal, frame, mode)
        width = max(4 * width, 8)
    return area, irr


@_jit()
def _rows(rows, width, area, irr, region, size, polys, counts, edges, start, owner, eye,
          normal, frame, mode):
    """`less` of the rows `rows` through scratch of `width` corners, into area, irr: the rows
    that found no room there (their measures not written)."""
    buf, d = np.empty((2, width, 2)), np.empty(width)
    left, many = np.empty(rows.shape[0], np.int64), 0
    for r in rows:
        ok = max(size[r], 3) <= width
        if ok:
            for j in range(size[r]):
                buf[0, j, 0], buf[0, j, 1] = region[r, j, 0], region[r, j, 1]
            seen = (eye[r, 0], eye[r, 1], eye[r, 2])
            turned = (normal[r, 0], normal[r, 1], normal[r, 2])
            whole_area, whole_irr = _ring(buf, 0, size[r], frame, mode, seen, turned)
            fan_area, fan_irr = 0.0, 0.0
            o = owner[r]
            for k in range(start[o], start[o + 1]):
                ax, ay, bx, by = edges[k, 0, 0], edges[k, 0, 1], edges[k, 1, 0], edges[k, 1, 1]
                signed = ax * by - ay * bx
                c = 3 if signed != 0 else 0
                # (centre, a, b), or (b, a, centre) where it turns clockwise
                first, last = (0, 2) if not signed < 0 else (2, 0)
                buf[0, first, 0], buf[0, first, 1] = 0.0, 0.0
                buf[0, 1, 0], buf[0, 1, 1] = ax, ay
                buf[0, last, 0], buf[0, last, 1] = bx, by
                s = 0
                for l in range(polys.shape[0]):
                    s, c, fits = _clip(polys, counts, l, r, buf, s, c, d)
                    ok &= fits
                if not ok:
                    break
                got_area, got_irr = _ring(buf, s, c, frame, mode, seen, turned)
                sign = 1.0 if signed > 0 else -1.0 if signed < 0 else 0.0 if signed == 0 \
                    else signed
                fan_area += sign * got_area
                fan_irr += sign * got_irr
            if ok:
                area[r], irr[r] = whole_area - fan_area, whole_irr - fan_irr
        if not ok:
            left[many] = r
            many += 1
    return left[:many]
