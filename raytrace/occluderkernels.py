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


@_jit()
def paired(welded):
    """`occluders._closed`'s first tests of triangles of welded corners (F, 3) in one pass:
    False where an edge runs from a corner to itself or sum f(a) g(b) over the edges a -> b
    differs from sum f(b) g(a) (`occluders._spread`'s mixes, uint64 products and sums
    wrapping: a closed surface's edges are their reverses, so the two are equal), and so
    the surface is certainly not closed; else True."""
    one, two = np.uint64(0), np.uint64(0)
    for t in range(welded.shape[0]):
        for e in range(3):
            a, b = welded[t, e], welded[t, (e + 1) % 3]
            if a == b:
                return False
            one += _mix(a, 1) * _mix(b, 2)
            two += _mix(b, 1) * _mix(a, 2)
    return one == two


@_jit(inline="always")
def _mix(i, seed):
    """`occluders._spread` of one id."""
    x = (np.uint64(i) + np.uint64(seed)) * np.uint64(0x9E3779B97F4A7C15)
    return x ^ (x >> np.uint64(29))


@_jit()
def cones(packed, members):
    """Each cluster's normal cone (C, 5), for `raytrace.blockkernels`' test of a cluster
    turned away from a block whole: its axis (the unit sum of its members' unit normals,
    packed's), the cosine of its half angle (the least of its members' normals along the
    axis, less 2^-40: every member's normal lies within it, the roundings too) and its sine
    (more 2^-40); the cosine -2 (no cluster passes that test) where a member has no normal,
    the sum is shorter than one member's or the half angle is not under 90 degrees (the
    test's bound, cos(f - t) at the angle f from the axis, holds for f >= t, which a bound
    under 0 then implies)."""
    out = np.empty((members.shape[0], 5))
    for c in range(members.shape[0]):
        sx = sy = sz = 0.0
        ok = True
        for k in range(members.shape[1]):
            if members[c, k] >= 0:
                nx, ny, nz = packed[c, k, 6], packed[c, k, 7], packed[c, k, 8]
                ok &= nx * nx + ny * ny + nz * nz > 0.5
                sx, sy, sz = sx + nx, sy + ny, sz + nz
        size = np.sqrt(sx * sx + sy * sy + sz * sz)
        out[c, 3] = -2.0
        if not (ok and size > 1.0):
            continue
        sx, sy, sz = sx / size, sy / size, sz / size
        least = 1.0
        for k in range(members.shape[1]):
            if members[c, k] >= 0:
                least = min(least, sx * packed[c, k, 6] + sy * packed[c, k, 7]
                            + sz * packed[c, k, 8])
        least -= 2.0 ** -40
        if not least > 0:
            continue
        out[c, 0], out[c, 1], out[c, 2], out[c, 3] = sx, sy, sz, least
        out[c, 4] = np.sqrt(max(0.0, 1.0 - least * least)) + 2.0 ** -40
    return out


@_jit()
def holes(welded, corners, owner, n_objects):
    """Each object's holes, for `raytrace.blockkernels`' one-way rule (numba only, as is the
    block path): a ball about each connected part of its boundary, the edges of its
    triangles (welded corner ids (M, 3), corners (M, 3, 3); owner (M,) each one's object,
    -1 for none) whose net count, lo -> hi against hi -> lo, is not zero (edges from a
    corner to itself left out: they bound nothing).  A fan from the ball's centre over the
    part's edges caps it, so the object and its caps are a closed surface whose caps lie in
    the balls.  (hole_at (n_objects + 1,) each object's first ball, centre (H, 3), radius
    (H,): the farthest of the part's corners from their mean, a little more).  Parts that
    share a corner across two objects' edges are one part of each (a coarser cap, as
    sound)."""
    m = welded.shape[0]
    # each edge (triangle * 3 + edge) under its lower corner id, then those of one lower id
    # matched by their higher one and object (a few each): one pass, no table at random
    span = welded.max() + 1 if m else 0
    first = np.zeros(span + 1, np.int64)
    for t in range(m):
        if owner[t] < 0:
            continue
        for e in range(3):
            a, z = welded[t, e], welded[t, (e + 1) % 3]
            if a != z:
                first[min(a, z) + 1] += 1
    first = np.cumsum(first)
    under, fill = np.empty(first[-1], np.int64), first[:-1].copy()
    high, way = np.empty(first[-1], np.int64), np.empty(first[-1], np.int64)
    for t in range(m):
        if owner[t] >= 0:
            for e in range(3):
                a, z = welded[t, e], welded[t, (e + 1) % 3]
                if a != z:
                    g = fill[min(a, z)]
                    under[g], high[g], way[g] = 3 * t + e, max(a, z), 1 if a < z else -1
                    fill[min(a, z)] += 1
    edges = np.empty(first[-1], np.int64)
    n_edges = 0
    for v in range(span):
        for j in range(first[v], first[v + 1]):
            if under[j] < 0:
                continue
            net, o = way[j], owner[under[j] // 3]
            for i in range(j + 1, first[v + 1]):
                if under[i] >= 0 and high[i] == high[j] and owner[under[i] // 3] == o:
                    net += way[i]
                    under[i] = -1
            if net != 0:
                edges[n_edges] = under[j]
                n_edges += 1
    edges = edges[:n_edges]
    # the boundary's parts: union-find over the corner ids of the edges left
    parent = np.arange(span)
    for g in edges:
        t, e = g // 3, g % 3
        ra, rz = _root(parent, welded[t, e]), _root(parent, welded[t, (e + 1) % 3])
        parent[max(ra, rz)] = min(ra, rz)
    key = np.empty(2 * len(edges), np.int64)
    for j in range(len(edges)):
        t, e = edges[j] // 3, edges[j] % 3
        for s in range(2):
            key[2 * j + s] = owner[t] * span + _root(parent, welded[t, (e + s) % 3])
    order = np.argsort(key, kind="mergesort")
    return _balls(key, order, edges, corners, span, n_objects)


@_jit()
def _root(parent, a):
    """a's root in the union-find parent, its path halved on the way."""
    while parent[a] != a:
        parent[a] = parent[parent[a]]
        a = parent[a]
    return a


@_jit()
def _balls(key, order, edges, corners, span, n_objects):
    """`holes`' balls: the corners of each part (key: object * span + root, two an edge,
    in order) about their mean, per object."""
    n = key.shape[0]
    hole_at = np.zeros(n_objects + 1, np.int64)
    centre, radius = np.empty((n // 2 + 1, 3)), np.empty(n // 2 + 1)
    h, j = 0, 0
    while j < n:
        k = j
        mean = np.zeros(3)
        while k < n and key[order[k]] == key[order[j]]:
            mean += _corner(order[k], edges, corners)
            k += 1
        mean /= k - j
        far = 0.0
        for i in range(j, k):
            d = _corner(order[i], edges, corners) - mean
            far = max(far, np.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]))
        centre[h], radius[h] = mean, far * (1 + 2.0 ** -20) + 1e-300
        hole_at[key[order[j]] // span + 1] += 1
        h, j = h + 1, k
    return np.cumsum(hole_at), centre[:h], radius[:h]


@_jit(inline="always")
def _corner(i, edges, corners):
    """The corner (3,) at end i % 2 of boundary edge i // 2."""
    t, e = edges[i // 2] // 3, edges[i // 2] % 3
    return corners[t, (e + i % 2) % 3].copy()


@_jit()
def hull_shadows(points, outward, offset, edges, sides, eye, center, normal, axes):
    """`occluders.Convex.shadows` in numba, one eye at a time: the same floats (the faces
    turned toward it and each corner carried as `polygons.dot` and `polygons.project` sum
    and divide; the mean as np.bincount sums) and the same order (a stable sort by angle)."""
    n, size = eye.shape[0], points.shape[0]
    toward, mark = np.empty(outward.shape[0], np.bool_), np.empty(size, np.bool_)
    xs, ys, angle = np.empty(size), np.empty(size), np.empty(size)
    order = np.empty(size, np.int64)
    at = np.zeros(n + 1, np.int64)
    out = np.empty((max(n * 8, 16), 2))
    for i in range(n):
        e0, e1, e2 = eye[i, 0], eye[i, 1], eye[i, 2]
        for f in range(outward.shape[0]):
            toward[f] = e0 * outward[f, 0] + e1 * outward[f, 1] + e2 * outward[f, 2] > offset[f]
        mark[:] = False
        for g in range(edges.shape[0]):
            if toward[sides[g, 0]] != toward[sides[g, 1]]:
                mark[edges[g, 0]], mark[edges[g, 1]] = True, True
        r0, r1, r2 = e0 - center[0], e1 - center[1], e2 - center[2]
        height = r0 * normal[0] + r1 * normal[1] + r2 * normal[2]
        base_u = r0 * axes[0, 0] + r1 * axes[0, 1] + r2 * axes[0, 2]
        base_v = r0 * axes[1, 0] + r1 * axes[1, 1] + r2 * axes[1, 2]
        k, sx, sy = 0, 0.0, 0.0
        for v in range(size):
            if not mark[v]:
                continue
            d0, d1, d2 = points[v, 0] - e0, points[v, 1] - e1, points[v, 2] - e2
            scale = height / -(d0 * normal[0] + d1 * normal[1] + d2 * normal[2])
            xs[k] = base_u + scale * (d0 * axes[0, 0] + d1 * axes[0, 1] + d2 * axes[0, 2])
            ys[k] = base_v + scale * (d0 * axes[1, 0] + d1 * axes[1, 1] + d2 * axes[1, 2])
            sx, sy, k = sx + xs[k], sy + ys[k], k + 1
        mx, my = sx / max(k, 1), sy / max(k, 1)
        for a in range(k):                       # by angle about the mean, stable
            angle[a] = np.arctan2(ys[a] - my, xs[a] - mx)
            w = a
            while w > 0 and angle[order[w - 1]] > angle[a]:
                order[w] = order[w - 1]
                w -= 1
            order[w] = a
        while at[i] + k > out.shape[0]:
            grown = np.empty((2 * out.shape[0], 2))
            grown[:at[i]] = out[:at[i]]
            out = grown
        for a in range(k):
            out[at[i] + a, 0], out[at[i] + a, 1] = xs[order[a]], ys[order[a]]
        at[i + 1] = at[i] + k
    return _padded(out, at)


@_jit()
def _padded(out, at):
    """Rows at (n + 1,) of out (c, 2) as (n, k, 2), each row's last corner repeated to the
    widest's k, and the counts (n,) (0 where fewer than 3)."""
    n = at.shape[0] - 1
    width = 1
    for i in range(n):
        width = max(width, at[i + 1] - at[i])
    flat, count = np.zeros((n, width, 2)), np.zeros(n, np.int64)
    for i in range(n):
        k = at[i + 1] - at[i]
        count[i] = k if k >= 3 else 0
        for a in range(width):
            g = at[i] + min(a, k - 1)
            if k > 0:
                flat[i, a, 0], flat[i, a, 1] = out[g, 0], out[g, 1]
    return flat, count
