"""The exact visibility's per-pixel loops in numba (the `fast` extra), where numpy's passes over
arrays of every (pixel, cluster) and (pixel, triangle) pair cost ~1 us a pair, most of it
moving those arrays through memory:

* `meets`: the clusters whose boxes meet a pixel's pyramid box and whose spheres no plane of
  the pyramid leaves wholly outside (`candidates.meets`);
* `pairs`: their triangles whose boxes meet it too, less those `candidates._keep` leaves
  out (the pixel's own, the coplanar, a convex object's own from outside, a closed one's
  faces toward p) (`candidates.pairs`);
* `cut`: each (pixel, triangle) pair decided and, where it crosses a plane, clipped in one
  pass over its corners (`pyramid.cut`); `uncut`, the whole shadows (`pyramid.uncut`);
* `inside`: convex polygons in the light's plane clipped by another's edges, one polygon
  at a time (`regions.inside`);
* `own_candidates`: a block's unsteady triangles paired with its pixels
  (`raytrace.blockwindings`).

The same answers and floats as numpy's paths, bit for bit: every signed distance is the same
three products summed left to right (`polygons.dot`), every new corner the same interpolation
(`polygons.clip`), every pair in the same order; tests/raytrace/test_exact_kernels.py and
test_candidates.py hold the two to the same bytes.  A kernel indexes scalars, not row views
(each view costs a reference count: the candidate query ran 13x slower with them).
"""

from __future__ import annotations

import numpy as np

from .packetkernels import _jit

# A triangle turns one way from p when p lies off its plane by more than this much of their
# distance (its unit normal . (p - corner) against |p - corner|): float64 products are good to
# ~1e-16 of it, and a triangle seen this nearly edge-on is left to the pixel's own pairs.
FACING = 2.0 ** -20


@_jit(inline="always")
def _clip_plane(src, n, dist, dst):
    """Sutherland-Hodgman of the polygon src[:n] (k, 3) by the plane of the corners' signed
    distances dist[:n], into dst: the kept corners and each crossing edge's new one, in
    `polygons.clip`'s order; returns the count."""
    m = 0
    for i in range(n):
        j = i + 1 if i + 1 < n else 0
        d0, d1 = dist[i], dist[j]
        if d0 >= 0:
            dst[m, 0], dst[m, 1], dst[m, 2] = src[i, 0], src[i, 1], src[i, 2]
            m += 1
        if (d0 >= 0) != (d1 >= 0):
            t = d0 / (d0 - d1)
            for a in range(3):
                dst[m, a] = src[i, a] + t * (src[j, a] - src[i, a])
            m += 1
    return m


@_jit()
def cut(corners, tri, pix, p, center, normal, sides, store):
    """Triangles corners[tri] (q,) against the pyramid from p[pix] (the light's plane through
    `center` with `normal`, then the side planes' inward normals sides (s, n, 3)), the pairs
    with something left, in order: (pieces (q', 4 + s, 3) zero past each count (with `store`;
    else (0, 4 + s, 3)), count (q',), whole (q',), their rows among the pairs (q',)); whole
    where all three corners are inside every plane (the piece is the triangle)."""
    q, s = tri.shape[0], sides.shape[0]
    width = 4 + s
    pieces = np.empty((q if store else 0, width, 3))
    count = np.empty(q, np.int64)
    whole = np.empty(q, np.bool_)
    rows = np.empty(q, np.int64)
    a, b = np.empty((width, 3)), np.empty((width, 3))
    dist = np.empty(width)
    d = np.empty(3)
    kept = 0
    for r in range(q):
        t, e = tri[r], pix[r]
        out, inside = True, True
        for k in range(3):
            d[k] = ((corners[t, k, 0] - center[0]) * normal[0]
                    + (corners[t, k, 1] - center[1]) * normal[1]
                    + (corners[t, k, 2] - center[2]) * normal[2])
            out &= d[k] < 0
            inside &= d[k] >= 0
        for j in range(s):
            if out:
                break
            beyond, within = True, True
            for k in range(3):
                x = ((corners[t, k, 0] - p[e, 0]) * sides[j, e, 0]
                     + (corners[t, k, 1] - p[e, 1]) * sides[j, e, 1]
                     + (corners[t, k, 2] - p[e, 2]) * sides[j, e, 2])
                beyond &= x < 0
                within &= x >= 0
            out = beyond
            inside &= within
        if out:
            continue
        if store or not inside:
            for k in range(3):
                for x in range(3):
                    a[k, x] = corners[t, k, x]
        n = 3
        if not inside:
            # crossing: clipped plane by plane, the distances taken afresh from each clip
            n = _clip_plane(a, 3, d, b)
            a, b = b, a
            for j in range(s):
                for k in range(n):
                    dist[k] = ((a[k, 0] - p[e, 0]) * sides[j, e, 0]
                               + (a[k, 1] - p[e, 1]) * sides[j, e, 1]
                               + (a[k, 2] - p[e, 2]) * sides[j, e, 2])
                n = _clip_plane(a, n, dist, b)
                a, b = b, a
            if n < 3:
                continue
        if store:
            for k in range(width):
                for x in range(3):
                    pieces[kept, k, x] = a[k, x] if k < n else 0.0
        count[kept], whole[kept], rows[kept] = n, inside, r
        kept += 1
    return pieces[:kept if store else 0], count[:kept], whole[:kept], rows[:kept]


@_jit()
def uncut(corners, tri, pix, p, top, center, normal, axes, reach):
    """`pyramid.uncut` of the pairs tri, pix (q,), top (n,) p's height over the light's
    plane: (flat (q, 3, 2), free (q,))."""
    q = tri.shape[0]
    flat = np.zeros((q, 3, 2))
    free = np.zeros(q, np.bool_)
    for r in range(q):
        t, e = tri[r], pix[r]
        ok = True
        for k in range(3):
            h = ((corners[t, k, 0] - center[0]) * normal[0]
                 + (corners[t, k, 1] - center[1]) * normal[1]
                 + (corners[t, k, 2] - center[2]) * normal[2])
            ok &= (h >= 0) & (h < top[e])
        if not ok:
            continue
        eye = seen_from(p, e, center, normal, axes)
        for k in range(3):
            flat[r, k, 0], flat[r, k, 1] = carried(corners, t, k, p, e, normal, axes, eye)
            ok &= (abs(flat[r, k, 0]) <= reach) & (abs(flat[r, k, 1]) <= reach)
        free[r] = ok
    return flat, free


@_jit(inline="always")
def seen_from(p, e, center, normal, axes):
    """p[e]'s height over the light's plane and its offset from the light's centre along
    each of the plane's axes (`polygons.project`'s sums), for `carried`."""
    rel0, rel1, rel2 = p[e, 0] - center[0], p[e, 1] - center[1], p[e, 2] - center[2]
    return (rel0 * normal[0] + rel1 * normal[1] + rel2 * normal[2],
            rel0 * axes[0, 0] + rel1 * axes[0, 1] + rel2 * axes[0, 2],
            rel0 * axes[1, 0] + rel1 * axes[1, 1] + rel2 * axes[1, 2])


@_jit(inline="always")
def carried(corners, t, k, p, e, normal, axes, eye):
    """Corner k of triangle t carried from p[e] onto the light's plane, in its coordinates
    (`polygons.project`'s arithmetic); eye: `seen_from` p[e]."""
    height, u, v = eye
    r0, r1 = corners[t, k, 0] - p[e, 0], corners[t, k, 1] - p[e, 1]
    r2 = corners[t, k, 2] - p[e, 2]
    scale = height / -(r0 * normal[0] + r1 * normal[1] + r2 * normal[2])
    return (u + scale * (r0 * axes[0, 0] + r1 * axes[0, 1] + r2 * axes[0, 2]),
            v + scale * (r0 * axes[1, 0] + r1 * axes[1, 1] + r2 * axes[1, 2]))


@_jit()
def meets(lo, hi, c_lo, c_hi, centre, radius, height, top, sides, p, among, run, r_lo, r_hi,
          r_centre, r_radius):
    """(n, C) bool: cluster c's box c_lo, c_hi (C, 3) meets pixel i's pyramid box lo, hi
    (n, 3), and its sphere centre (C, 3), radius (C,) is not wholly below the light's plane
    (height (C,) its centre's over it), above p's parallel plane (top (n,) p's height), or
    outside a side plane (sides (s, n, 3) unit inward normals through p (n, 3)); among (n,
    C) bool: only those clusters tested (the rest False), or (0, 0): every one.  The
    clusters come in runs of `run` with a box r_lo, r_hi (R, 3) and a sphere r_centre (R,
    3), r_radius (R,) holding theirs (`occluders.Objects`): a run whose box misses the
    pixel's, or whose sphere lies outside a side plane by more than its products' rounding
    (2^-40 of the coordinates' sizes, L1), is passed over at once."""
    n, c_n = lo.shape[0], c_lo.shape[0]
    out = np.zeros((n, c_n), np.bool_)
    every = among.shape[0] == 0
    for i in range(n):
        for r in range(r_lo.shape[0]):
            if not _boxes_meet(r_lo, r_hi, r, lo, hi, i):
                continue
            size = abs(r_centre[r, 0]) + abs(r_centre[r, 1]) + abs(r_centre[r, 2]) + \
                abs(p[i, 0]) + abs(p[i, 1]) + abs(p[i, 2]) + r_radius[r]
            if not _inside_sides(r_centre, r, r_radius[r] + 2.0 ** -40 * size, i, p, sides):
                continue
            for c in range(r * run, min(r * run + run, c_n)):
                if not (every or among[i, c]) or not _boxes_meet(c_lo, c_hi, c, lo, hi, i):
                    continue
                out[i, c] = (height[c] >= -radius[c]) & (height[c] <= top[i] + radius[c]) \
                    and _inside_sides(centre, c, radius[c], i, p, sides)
    return out


@_jit(inline="always")
def _boxes_meet(a_lo, a_hi, k, b_lo, b_hi, i):
    """Whether box k of a_lo, a_hi (., 3) meets box i of b_lo, b_hi (., 3)."""
    ok = True
    for a in range(3):
        ok &= (a_lo[k, a] <= b_hi[i, a]) & (a_hi[k, a] >= b_lo[i, a])
    return ok


@_jit(inline="always")
def coplanar_with(corners, t, o, m0, m1, m2, tri_normal, offset, scale_t, scale_o, coplanar):
    """Whether triangle t (unit normal m0, m1, m2, scale_t) is coplanar with p's own triangle
    o (`candidates._keep`'s rule: nearly parallel, and every corner within COPLANAR_RELATIVE,
    `coplanar`, of the larger scale of o's plane; tri_normal, offset (M,): `Objects`)."""
    n0, n1, n2 = tri_normal[o, 0], tri_normal[o, 1], tri_normal[o, 2]
    if not abs(n0 * m0 + n1 * m1 + n2 * m2) > 1 - 1e-3:
        return False
    off = 0.0
    for j in range(3):
        off = max(off, abs(corners[t, j, 0] * n0 + corners[t, j, 1] * n1
                           + corners[t, j, 2] * n2 - offset[o]))
    return not off > coplanar * max(scale_o, scale_t)


@_jit(inline="always")
def _inside_sides(centre, k, reach, i, p, sides):
    """Whether the sphere about centre[k] of radius `reach` is not wholly outside a side
    plane of pixel i's pyramid (sides (s, n, 3) unit inward normals through p (n, 3))."""
    ok = True
    for j in range(sides.shape[0]):
        if not ok:
            break
        m0, m1, m2 = sides[j, i, 0], sides[j, i, 1], sides[j, i, 2]
        at = m0 * centre[k, 0] + m1 * centre[k, 1] + m2 * centre[k, 2]
        ok = at - (m0 * p[i, 0] + m1 * p[i, 1] + m2 * p[i, 2]) >= -reach
    return ok


@_jit()
def _box_pairs(met, met_at, members, packed, kinds, lo, hi, own, tri_normal, offset, scale,
               obj, outside, clear, corners, p, coplanar, pix, tri):
    """The pairs of `pairs` into pix, tri where given (else only counted): their number;
    met (k,): the clusters that meet each pixel, pixel i's from met_at[i] to met_at[i + 1].
    Each member's own fields come from packed and kinds (`occluders.Objects`), in order and
    indexed one by one (a view of a row costs a reference count); only a near-parallel
    one's corners are read apart."""
    q = 0
    for i in range(met_at.shape[0] - 1):
        o = own[i]
        for g in range(met_at[i], met_at[i + 1]):
            c = met[g]
            for k in range(members.shape[1]):
                t = members[c, k]
                if t < 0 or t == o:
                    continue
                ok = True
                for a in range(3):
                    ok &= (packed[c, k, a] <= hi[i, a]) & (packed[c, k, 3 + a] >= lo[i, a])
                if not ok:
                    continue
                if coplanar_with(corners, t, o, packed[c, k, 6], packed[c, k, 7],
                                 packed[c, k, 8], tri_normal, offset, packed[c, k, 15],
                                 scale[o], coplanar):
                    continue
                kind = kinds[c, k]
                # a convex object's own triangles from its outside
                if kind & 1 and kind // 4 == obj[o] and outside[i]:
                    continue
                # a closed object's triangles that face p, where the light is outside it
                if kind & 2 and clear.shape[0] and clear[kind // 4] and (
                        packed[c, k, 9] * (packed[c, k, 12] - p[i, 0])
                        + packed[c, k, 10] * (packed[c, k, 13] - p[i, 1])
                        + packed[c, k, 11] * (packed[c, k, 14] - p[i, 2])) <= 0:
                    continue
                if pix.shape[0]:
                    pix[q], tri[q] = i, t
                q += 1
    return q


@_jit()
def pairs(meet, members, packed, kinds, lo, hi, own, tri_normal, offset, scale, obj, outside,
          clear, corners, p, coplanar):
    """(pix (q,), tri (q,)) int64: for each pixel i and cluster c that meet (n, C), in that
    order, the members (C, K) (-1 pads) whose boxes meet lo, hi (n, 3), bar own (n,), that
    `candidates._keep` keeps: packed, kinds (`occluders.Objects`), the triangles' normal,
    offset, scale and object (M,), outside (n,) p outside its own convex object, clear
    (n_objects,) or empty for none, the corners (M, 3, 3), p (n, 3), COPLANAR_RELATIVE."""
    none = np.zeros(0, np.int64)
    # the meeting clusters listed once, pixel by pixel (both passes read the list, not the
    # (n, C) matrix: most of a pixel's row is False)
    met_at = np.zeros(meet.shape[0] + 1, np.int64)
    for i in range(meet.shape[0]):
        k = 0
        for c in range(meet.shape[1]):
            k += meet[i, c]
        met_at[i + 1] = met_at[i] + k
    met = np.empty(met_at[-1], np.int64)
    for i in range(meet.shape[0]):
        g = met_at[i]
        for c in range(meet.shape[1]):
            if meet[i, c]:
                met[g] = c
                g += 1
    args = (met, met_at, members, packed, kinds, lo, hi, own, tri_normal, offset, scale, obj,
            outside, clear, corners, p, coplanar)
    q = _box_pairs(*args, none, none)
    pix, tri = np.empty(max(q, 1), np.int64), np.empty(max(q, 1), np.int64)
    _box_pairs(*args, pix, tri)
    return pix[:q], tri[:q]


@_jit()
def inside(cut, count, inner, inner_count, room=1):
    """`regions.inside`: the convex polygons inner (n, m, 2), inner_count (n,) clipped by
    each edge of the convex counter-clockwise polygons cut (n, k, 2), count (n,): (corners
    (n, w, 2), w at least room (m + k), zero past each count, counts (n,)).  A convex clip
    makes m + k corners at most, but rounding can put two where one belongs, so where a
    row's corners would not fit its scratch (twice w) or w, every row is clipped again in
    four times as much: numba writes past no array's end unchecked."""
    width = max(room * (inner.shape[1] + cut.shape[1]), 1)
    while True:
        out, got, fits = _inside(cut, count, inner, inner_count, width)
        if fits:
            return out, got
        width *= 4


@_jit()
def _inside(cut, count, inner, inner_count, width):
    """`inside` with `width` corners a row: (corners, counts, whether every row fit: False
    at the first that did not, the rest left undone)."""
    n = inner.shape[0]
    out = np.zeros((n, width, 2))
    got = np.zeros(n, np.int64)
    buf = np.empty((2, 2 * width, 2))
    d = np.empty(2 * width)
    for r in range(n):
        c, s = inner_count[r], 0
        if c > width:
            return out, got, False
        for j in range(c):
            buf[0, j, 0], buf[0, j, 1] = inner[r, j, 0], inner[r, j, 1]
        for e in range(count[r]):
            if 2 * c > buf.shape[1]:
                return out, got, False
            f = e + 1 if e + 1 < count[r] else 0
            s0, s1 = cut[r, e, 0], cut[r, e, 1]
            c = keep_left(buf, s, c, s0, s1, cut[r, f, 0] - s0, cut[r, f, 1] - s1, d)
            s = 1 - s
        if c > width:
            return out, got, False
        for j in range(c):
            out[r, j, 0], out[r, j, 1] = buf[s, j, 0], buf[s, j, 1]
        got[r] = c
    return out, got, True


@_jit(inline="always")
def keep_left(buf, s, c, s0, s1, e0, e1, d):
    """The polygon buf[s, :c] (2, m, 2) cut to the left of the line through (s0, s1) along
    (e0, e1) into buf[1 - s] (`regions.inside`'s arithmetic for one edge): their count (at
    most 2 c); d (c,) scratch.  `raytrace.measurekernels` clips its fans by it too.  One
    buffer and the side it reads, not two arrays swapped at each edge, and every read before
    a branch: numba counts references to an array an inlined function reads under a branch,
    or that a loop replaces, on every call (docs/speed.md, "Reference counts")."""
    w = 1 - s                                            # the side written
    for j in range(c):
        d[j] = e0 * (buf[s, j, 1] - s1) - e1 * (buf[s, j, 0] - s0)
    q = 0
    for i in range(c):
        j = i + 1 if i + 1 < c else 0
        di, dj = d[i], d[j]
        ai0, ai1, aj0, aj1 = buf[s, i, 0], buf[s, i, 1], buf[s, j, 0], buf[s, j, 1]
        if di >= 0:
            buf[w, q, 0], buf[w, q, 1] = ai0, ai1
            q += 1
        if (di >= 0) != (dj >= 0):
            t = di / (di - dj)
            buf[w, q, 0] = ai0 + t * (aj0 - ai0)
            buf[w, q, 1] = ai1 + t * (aj1 - ai1)
            q += 1
    return q


@_jit()
def own_candidates(block, unsteady, to_cut, u_at, own, tri_lo, tri_hi, lo, hi, tri_normal,
                   offset, scale, corners, coplanar, p, u_way, sides):
    """Each pixel's pairs of its block's unsteady triangles (`blockkernels.block_edges`;
    `blockwindings._own_pairs`): (pix, tri (f,): those free from every pixel of the block
    and not wholly outside a side plane of the pixel's pyramid (sides (s, n, 3) their unit
    inward normals: `_outside`); pix, tri (k,): of the others (to_cut (u,)), those whose
    boxes (tri_lo, tri_hi (M, 3)) meet the pixel's pyramid's box lo, hi (n, 3), bar its own
    triangle and those coplanar with it (`candidates._keep`:
    its other rules never apply here, as no block that meets a convex object's cluster has
    unsteady triangles, `blockwindings.chains`, and no closed object's faces are left out),
    each by pixel, in the order of unsteady; block (n,) each pixel's, u_at (b + 1,);
    tri_normal, offset, scale (M,): `occluders.Objects`; coplanar: COPLANAR_RELATIVE; but
    none free from every pixel that may be left out (u_way (u,), `block_edges`) and is
    turned away from the pixel's p (n, 3) (off its plane by more than FACING of their
    distance, behind it).  One not free from some pixel is kept: left out, its cut pieces
    moved a contact pixel's V by up to 7e-11 against the pixel path (the bunny 128x128)."""
    n = block.shape[0]
    total = 0
    for i in range(n):
        total += u_at[block[i] + 1] - u_at[block[i]]
    f_pix, f_tri = np.empty(total, np.int64), np.empty(total, np.int64)
    k_pix, k_tri = np.empty(total, np.int64), np.empty(total, np.int64)
    f = k = 0
    for i in range(n):
        o = own[i]
        for g in range(u_at[block[i]], u_at[block[i] + 1]):
            t = unsteady[g]
            if not to_cut[g]:
                if not (u_way[g] and _away(t, i, p, tri_normal, corners)
                        or _outside(t, i, p, corners, sides)):
                    f_pix[f], f_tri[f] = i, t
                    f += 1
                continue
            if t == o or not _boxes_meet(tri_lo, tri_hi, t, lo, hi, i) or coplanar_with(
                    corners, t, o, tri_normal[t, 0], tri_normal[t, 1], tri_normal[t, 2],
                    tri_normal, offset, scale[t], scale[o], coplanar):
                continue
            k_pix[k], k_tri[k] = i, t
            k += 1
    return f_pix[:f], f_tri[:f], k_pix[:k], k_tri[:k]


@_jit(inline="always")
def _outside(t, i, p, corners, sides):
    """Whether triangle t lies wholly outside a side plane of pixel i's pyramid (sides (s,
    n, 3) unit inward normals through p (n, 3)): each corner below it by more than 2^-40 of
    its distance (L1) from p_i, for the products' rounding and the plane's."""
    for j in range(sides.shape[0]):
        m0, m1, m2 = sides[j, i, 0], sides[j, i, 1], sides[j, i, 2]
        out = True
        for k in range(3):
            r0, r1, r2 = corners[t, k, 0] - p[i, 0], corners[t, k, 1] - p[i, 1], \
                corners[t, k, 2] - p[i, 2]
            out &= m0 * r0 + m1 * r1 + m2 * r2 < -2.0 ** -40 * (abs(r0) + abs(r1) + abs(r2))
        if out:
            return True
    return False


@_jit(inline="always")
def _away(t, i, p, tri_normal, corners):
    """Whether triangle t is turned away from p_i: p_i behind its plane by more than FACING
    of p_i's distance from its first corner (`facingkernels._steady`'s test)."""
    r0, r1, r2 = p[i, 0] - corners[t, 0, 0], p[i, 1] - corners[t, 0, 1], \
        p[i, 2] - corners[t, 0, 2]
    s = tri_normal[t, 0] * r0 + tri_normal[t, 1] * r1 + tri_normal[t, 2] * r2
    return s < -FACING * np.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
