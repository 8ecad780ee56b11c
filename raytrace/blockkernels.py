"""A block of pixels' shared outline, in numba (`raytrace.blockwindings`).

Pixels a few apart see most triangles from the same side.  A triangle that every point p of
a block sees turned the same way, certainly (p off its plane by more than FACING of their
distance), and that is free from each (`pyramid.uncut`; `raytrace.facingkernels`, mostly
from the block's first point alone) casts a shadow that turns the same way from each;
where two such triangles share an edge and turn the same way it cancels from every
pixel's outline (`raytrace.windings`).  So the block's steady
triangles are counted once, edge by edge, and only the edges left (the block's outline: its
rim, its folds, its borders with the unsteady triangles) are carried from each pixel; the
unsteady triangles (turned either way within the block, not free, a pixel's own or coplanar
with it) are the pixels' own pairs, as before.  The steady ones are all the triangles of the
clusters that meet any of the block's pyramids, also those whose shadows miss a pixel's
light: what they add lies outside the light, and the outline is cut to a box about it
(`raytrace.clipkernels`).

Where an object and its holes' caps wind 0 times about the block's points and the light, its
triangles turned away from every point of the block are left out, but for those a segment
through a hole may meet (`raytrace.onewaykernels`, the one-way rule).  A cluster whose
sphere, normal cone (`occluderkernels.cones`) and heights show every member so (turned away
from each point, free from each, within reach: `_behind`) is passed over whole, its members
untested unless the rule turns out off or a hole's cone meets it (a quarter of the clusters
met on the bunny 128 x 128; `block_edges` ~0.95x, the same bytes).

`block_edges` makes room for a block's unsteady triangles (as many as its clusters hold) and
for its outline edges before its loops, never within them: numba counts references to an
array a loop may replace, on every pass (docs/speed.md, "Reference counts"); it calls no
function for a member that is not inlined (a call counts references to each array it is
handed: the one-way rule's tests wait for `onewaykernels.settle`, once a block); and it
hands `_behind`, once a cluster and pixel, floats: handed the arrays, with its loop over
the pixels and its early returns, it counted their references at each call (10 atomic
adds and subtracts a cluster; ~5 % of `block_edges` on the bunny 128 x 128).
"""

from __future__ import annotations

import numpy as np

# own_candidates lives with the pixel path's pair kernels; the block path takes it from here
# with its other kernels (`raytrace.blockwindings`), so it runs wherever they load
from .exactkernels import FACING, carried, own_candidates, seen_from  # noqa: F401
from .facingkernels import _ahead, _behind, _distinct, _facing, _mine, _steady, _tops
from .onewaykernels import boxes_touch, clear, kept, settle, spot
from .outlinekernels import _apart, _level, _tally
from .packetkernels import _jit


@_jit()
def block_edges(start, meet, members, packed, kinds, welded, h, p, top, own, tri_normal,
                offset, scale, corners, rel, reach, coplanar, sides, most, ways):
    """For the blocks of pixels start (b + 1,), of the triangles `_near` keeps: the outline
    edges (tri, from, to (e,): a triangle, the corners (0-2) the edge runs between the way its
    net count (e,) is positive; each block's start (b + 1,)); the unsteady triangles (u,),
    whether each is free from some pixels only or one's own or coplanar with it (u,), each
    block's start (b + 1,); whether a block has a convex object's triangle (b,) (a guard:
    the pixel path unites those as hulls); whether each unsteady triangle may be left out
    where it turns away from a pixel (u,) (`onewaykernels`).  meet (b, C): the clusters
    meeting some pixel's pyramid of each block (sides (s, n, 3): their unit inward normals);
    h (C, CLUSTER, 3): the members' corners' heights over the light's plane; top (n,): p's;
    rel (n,) |p - centre|; reach: UNCUT_REACH of the light; most: the most triangles a
    block's clusters hold; ways: `blockwindings.chains`' (`_ways`', `_behind`'s)."""
    n_blocks, width, owner, one_way = start.shape[0] - 1, members.shape[1], ways[0], ways[1]
    centre, radius, cones, spans = ways[5], ways[6], ways[7], ways[8]
    e_tri, e_from, e_to, e_cnt, unsteady, loose, u_c, u_way = _rooms(1024)
    e_at, u_at = np.zeros(n_blocks + 1, np.int64), np.zeros(n_blocks + 1, np.int64)
    convex = np.zeros(n_blocks, np.bool_)
    # a block's steady edges (lo, hi, way, its triangle and corners), its members turned away,
    # then those in doubt (cluster, member); per object and cluster the one-way rule's state
    keys, later = np.empty((6, 3 * most), np.int64), np.empty((2, 2 * most), np.int64)
    way, seen = np.zeros(one_way.shape[0], np.bool_), np.full(one_way.shape[0], -1, np.int64)
    cone, axes = np.full(meet.shape[1], -1, np.int64), np.empty((ways[3].shape[0], 6))
    ne = nu = np.int64(0)         # not a literal (`windingkernels.boundaries`)
    slack, box, owns = np.empty(sides.shape[0]), np.empty(7), np.empty(p.shape[0], np.int64)
    for b in range(n_blocks):
        i0, i1 = start[b], start[b + 1]
        low_top, high_top, far_rel, ball = _tops(i0, i1, top, rel, p)
        n_own, q, nd, nt = _distinct(i0, i1, own, owns), 0, 0, 0
        unsteady, loose, u_c, u_way = _room(unsteady, loose, u_c, u_way, nu, most)
        _slacks(i0, i1, p, sides, slack)
        spot(i0, i1, p, box)
        for c in range(meet.shape[1]):
            if not meet[b, c]:
                continue
            o = owner[c]
            if seen[o] != b:
                seen[o], way[o] = b, one_way[o] and _ways(o, i0, i1, p, ways, axes, sides, slack)
            # `_behind` from each p: every member turned away, free, within reach
            grow = _ahead(cones[c, 3], spans[c, 0], spans[c, 1], low_top, high_top)
            whole = way[o] and grow >= 0
            for i in range(i0, i1):
                whole = whole and _behind(
                    p[i, 0] - centre[c, 0], p[i, 1] - centre[c, 1], p[i, 2] - centre[c, 2],
                    cones[c, 0], cones[c, 1], cones[c, 2], cones[c, 3], cones[c, 4], radius[c],
                    grow, far_rel, reach)
            if whole:
                later[0, nd], later[1, nd], nd = c, -1, nd + 1     # turned away, whole
                continue
            for k in range(width):
                t = members[c, k]
                if t < 0 or not _near(c, k, i0, packed, p, sides, slack):
                    continue
                convex[b] |= kinds[c, k] & 1 != 0
                hint, shape = _facing(c, k, packed, h, ball, low_top, high_top, far_rel, reach)
                mine = _mine(t, c, k, packed, owns, n_own, corners, tri_normal, offset, scale,
                             coplanar)
                sign = (0 if mine else hint) if hint != 0 else _steady(
                    c, k, i0, i1, packed, shape, p, low_top, high_top, far_rel, reach, mine)
                if sign == 1 or sign == -1:
                    if sign < 0 and way[o]:             # `_turned_away` pushes it or not
                        later[0, nd], later[1, nd] = c, k
                        nd += 1
                    else:
                        q = _push(q, sign, c, k, t, welded, keys)
                    continue
                if way[o] and boxes_touch(c, k, packed, box, FACING):    # `settle` tests it
                    later[0, most + nt], later[1, most + nt] = c, k
                    nt += 1
                if sign != 3:
                    unsteady[nu], loose[nu], u_c[nu] = t, sign == 0, c
                    nu += 1
        settle(nt, later, most, u_at[b], nu, u_c, u_way, b, i0, i1, p, own, way, cone, axes,
               ways, members, (packed, corners, tri_normal, offset, scale, coplanar, FACING))
        q = _turned_away(q, nd, later, b, i0, p, way, cone, axes, ways, members, packed,
                         welded, keys, sides, slack)
        e_tri, e_from, e_to, e_cnt, ne = _collect(q, keys, e_tri, e_from, e_to, e_cnt, ne)
        e_at[b + 1], u_at[b + 1] = ne, nu
    return e_tri[:ne], e_from[:ne], e_to[:ne], e_cnt[:ne], e_at, unsteady[:nu], loose[:nu], \
        u_at, convex, u_way[:nu]


@_jit()
def _rooms(n):
    """`block_edges`' growing arrays, n long: its outline edges' tri, from, to, count, its
    unsteady triangles, whether each is loose, its cluster, whether it may be left out."""
    return np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.int64), \
        np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.bool_), \
        np.empty(n, np.int64), np.empty(n, np.bool_)


@_jit()
def _turned_away(q, nd, later, b, i0, p, way, cone, axes, ways, members, packed, welded, keys,
                 sides, slack):
    """Block b's members turned away from each of its points (later[:, :nd]: cluster and
    member, or -1 for each near member of a cluster `_behind` passed), pushed into keys from
    q where their object is off the one-way rule or their cluster meets a hole's cone
    (`onewaykernels.kept`), in their order: the next q."""
    owner = ways[0]
    for g in range(nd):
        c, k = later[0, g], later[1, g]
        if way[owner[c]]:
            if not (cone[c] >= 0 and cone[c] >> 1 == b):
                kept(c, b, i0, p, cone, ways, axes)
            if cone[c] & 1 == 0:
                continue
        if k >= 0:
            q = _push(q, -1, c, k, members[c, k], welded, keys)
            continue
        for k in range(members.shape[1]):           # as the member loop would have pushed
            if members[c, k] >= 0 and _near(c, k, i0, packed, p, sides, slack):
                q = _push(q, -1, c, k, members[c, k], welded, keys)
    return q


@_jit(inline="always")
def _push(q, sign, c, k, t, welded, keys):
    """Member k of cluster c (triangle t), turned `sign` from the block, pushed as its three
    edges (its winding made positive) into keys (6, room) from q: the next q."""
    for e in range(3):
        a, z = (e, (e + 1) % 3) if sign > 0 else ((e + 1) % 3, e)
        ka, kb = welded[c, k, a], welded[c, k, z]
        keys[0, q], keys[1, q], keys[2, q] = min(ka, kb), max(ka, kb), 1 if ka < kb else -1
        keys[3, q], keys[4, q], keys[5, q] = t, a, z
        q += 1
    return q


@_jit()
def _collect(q, keys, e_tri, e_from, e_to, e_cnt, ne):
    """The block's outline edges from the tally (`outlinekernels._tally`) of its pushed
    edges, keys' (6, q) lo, hi, way, written from ne on, each from its first edge's triangle
    and corners (keys' last three), run the way its net count is positive: (the edges'
    arrays, grown where full, the next ne)."""
    first, net = _tally(keys[0, :q], keys[1, :q], keys[2, :q])
    while ne + first.shape[0] > e_tri.shape[0]:
        e_tri, e_from = _grow(e_tri, ne), _grow(e_from, ne)
        e_to, e_cnt = _grow(e_to, ne), _grow(e_cnt, ne)
    for g in range(first.shape[0]):
        f = first[g]
        # the first edge runs lo -> hi where way > 0; the net where net > 0
        forward = (keys[2, f] > 0) == (net[g] > 0)
        e_tri[ne] = keys[3, f]
        e_from[ne], e_to[ne] = (keys[4, f], keys[5, f]) if forward else (keys[5, f], keys[4, f])
        e_cnt[ne] = abs(net[g])
        ne += 1
    return e_tri, e_from, e_to, e_cnt, ne


@_jit()
def _ways(o, i0, i1, p, ways, axes, sides, slack):
    """Whether object o may take the one-way rule in the block of pixels i0..i1
    (`onewaykernels.clear`), with its holes' axes made; a hole whose ball lies below a
    lowered side plane of the first p's pyramid meets no pixel's pyramid (`_near`): no
    segment from a p to the light crosses its cap, and its sine is -1 (none of its cone
    is kept)."""
    out = clear(o, i0, i1, p, ways, axes)
    at, centre, radius = ways[2], ways[3], ways[4]
    for g in range(at[o], at[o + 1]):
        if not _above(centre[g, 0], centre[g, 1], centre[g, 2], radius[g] * (1 + 2.0 ** -20),
                      i0, p, sides, slack):
            axes[g, 3] = -1.0
    return out


@_jit(inline="always")
def _slacks(i0, i1, p, sides, slack):
    """slack (s,): how far (<= 0) below each side plane of pixel i0's pyramid (sides (s, n, 3)
    unit inward normals through p (n, 3)) the block's other pixels i0..i1 lie, the least."""
    for j in range(sides.shape[0]):
        m0, m1, m2 = sides[j, i0, 0], sides[j, i0, 1], sides[j, i0, 2]
        least = 0.0
        for i in range(i0 + 1, i1):
            least = min(least, m0 * (p[i, 0] - p[i0, 0]) + m1 * (p[i, 1] - p[i0, 1])
                        + m2 * (p[i, 2] - p[i0, 2]))
        slack[j] = least


@_jit(inline="always")
def _near(c, k, i0, packed, p, sides, slack):
    """Whether member k of cluster c may meet the pyramid of some pixel of the block of pixel
    i0: its box's sphere (packed: its box) not wholly below a side plane of i0's pyramid
    lowered by its slack (`_slacks`).  A pixel i's pyramid is the hull of p_i and the light's
    base, which lies on each plane's inner side, so its points are no lower than p_i below
    each (the plane holds the base's edge); a point of the triangle lies in its sphere; and
    2^-40 of the centre's distance (L1) from p_i0 covers the products' rounding."""
    c0 = (packed[c, k, 0] + packed[c, k, 3]) / 2
    c1 = (packed[c, k, 1] + packed[c, k, 4]) / 2
    c2 = (packed[c, k, 2] + packed[c, k, 5]) / 2
    d0, d1 = packed[c, k, 3] - packed[c, k, 0], packed[c, k, 4] - packed[c, k, 1]
    d2 = packed[c, k, 5] - packed[c, k, 2]
    radius = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) / 2 * (1 + 2.0 ** -30) + 1e-300
    return _above(c0, c1, c2, radius, i0, p, sides, slack)


@_jit(inline="always")
def _above(c0, c1, c2, radius, i0, p, sides, slack):
    """Whether the sphere about c0, c1, c2 of `radius` is not wholly below a side plane of
    pixel i0's pyramid lowered by its slack (`_near`), 2^-40 of the centre's distance (L1)
    from p_i0 added to the radius for the products' rounding."""
    r0, r1, r2 = c0 - p[i0, 0], c1 - p[i0, 1], c2 - p[i0, 2]
    reach = radius + 2.0 ** -40 * (abs(r0) + abs(r1) + abs(r2))
    inside = True
    for j in range(sides.shape[0]):
        inside &= sides[j, i0, 0] * r0 + sides[j, i0, 1] * r1 + sides[j, i0, 2] * r2 >= \
            slack[j] - reach
    return inside


@_jit()
def block_meets(start, lo, hi, top, sides, p, c_lo, c_hi, centre, radius, height, size, hull,
                run, r_lo, r_hi, r_centre, r_radius):
    """(b, C) bool: cluster c may meet the pyramid of some pixel of block b (start (b + 1,)),
    and per block (b,) the triangles of those clusters (size (C,) each's) and whether one of
    them is a convex object's (hull (C,)):
    `candidates.meets` of the block, its box meeting the box of the pixels' pyramids' boxes
    lo, hi (n, 3), its sphere (centre (C, 3), radius (C,), the centre's height (C,) over the
    light's plane) reaching between that plane and the highest pixel's parallel one (top
    (n,)), and not outside a side plane of every pixel's pyramid (sides (s, n, 3) unit
    inward normals through p (n, 3)); the last tested first as `_near` tests a triangle (the
    first pixel's planes lowered by the block's slack: four products leave out most
    clusters), then pixel by pixel.  The clusters come in runs of `run`, each run's box r_lo,
    r_hi (R, 3) and a sphere r_centre (R, 3), r_radius (R,) that holds its clusters' spheres
    (`occluders.Objects`): a run whose box misses the block's, or whose sphere lies below a
    lowered side plane, is passed over at once (a block's pyramids meet ~1 % of the bunny's
    clusters; ~10 % lie in their box)."""
    n_blocks, n_c = start.shape[0] - 1, c_lo.shape[0]
    out = np.zeros((n_blocks, n_c), np.bool_)
    many, convex = np.zeros(n_blocks, np.int64), np.zeros(n_blocks, np.bool_)
    low, high = np.empty(3), np.empty(3)
    slack = np.empty(sides.shape[0])
    for b in range(n_blocks):
        i0, i1 = start[b], start[b + 1]
        _slacks(i0, i1, p, sides, slack)
        most = top[i0]
        for a in range(3):
            low[a], high[a] = lo[i0, a], hi[i0, a]
        for i in range(i0 + 1, i1):
            most = max(most, top[i])
            for a in range(3):
                low[a], high[a] = min(low[a], lo[i, a]), max(high[a], hi[i, a])
        for r in range(r_lo.shape[0]):
            if not (r_lo[r, 0] <= high[0] and r_hi[r, 0] >= low[0]
                    and r_lo[r, 1] <= high[1] and r_hi[r, 1] >= low[1]
                    and r_lo[r, 2] <= high[2] and r_hi[r, 2] >= low[2]):
                continue
            # its sphere below a lowered side plane, by more than the products' rounding at
            # its clusters' own tests, too: 2^-36 of the coordinates' sizes (a run's sphere
            # may be far smaller than its distance from p, and its 2^-30 of the radius then
            # less than a rounding; not seen to matter in 3,000 adversarial runs, but cheap)
            extent = abs(r_centre[r, 0]) + abs(r_centre[r, 1]) + abs(r_centre[r, 2]) + \
                abs(p[i0, 0]) + abs(p[i0, 1]) + abs(p[i0, 2])
            if not _above(r_centre[r, 0], r_centre[r, 1], r_centre[r, 2],
                          r_radius[r] + 2.0 ** -36 * extent, i0, p, sides, slack):
                continue
            for c in range(r * run, min(r * run + run, n_c)):
                if not (c_lo[c, 0] <= high[0] and c_hi[c, 0] >= low[0]
                        and c_lo[c, 1] <= high[1] and c_hi[c, 1] >= low[1]
                        and c_lo[c, 2] <= high[2] and c_hi[c, 2] >= low[2]):
                    continue
                if not (height[c] >= -radius[c] and height[c] <= most + radius[c]):
                    continue
                # its sphere wholly below a side plane of i0's pyramid lowered by the slack:
                # it meets no pixel's pyramid of the block (`_near`)
                if not _above(centre[c, 0], centre[c, 1], centre[c, 2], radius[c], i0, p,
                              sides, slack):
                    continue
                for i in range(i0, i1):             # then as each pixel sees it
                    inside = True
                    for j in range(sides.shape[0]):
                        inside &= sides[j, i, 0] * (centre[c, 0] - p[i, 0]) \
                            + sides[j, i, 1] * (centre[c, 1] - p[i, 1]) \
                            + sides[j, i, 2] * (centre[c, 2] - p[i, 2]) >= -radius[c]
                    if inside:
                        out[b, c] = True
                        many[b] += size[c]
                        convex[b] |= hull[c]
                        break
    return out, many, convex


@_jit()
def _room(unsteady, loose, u_c, u_way, nu, most):
    """`block_edges`' unsteady arrays, their first nu kept, with room for most more (its
    room is made before its loops: see the module docstring)."""
    while nu + most > unsteady.shape[0]:
        unsteady, loose = _grow(unsteady, nu), _grow(loose, nu)
        u_c, u_way = _grow(u_c, nu), _grow(u_way, nu)
    return unsteady, loose, u_c, u_way


@_jit()
def _grow(a, n):
    """a with twice the room, its first n kept."""
    out = np.empty(2 * a.shape[0], a.dtype)
    out[:n] = a[:n]
    return out


@_jit()
def carried_edges(start, e_tri, e_from, e_to, e_cnt, e_at, corners, welded, p, center, normal,
                  axes, box):
    """Each block's outline edges (`block_edges`) carried from each of its pixels (start (b +
    1,)) onto the light's plane: (flat (q, 2, 2), ids (q, 2), count (q,), pixel (q,)), by
    pixel; only those that meet the box (4,) x0, y0, x1, y1 or cross the level y0 of its
    first corner (an edge from y0 up, or down to it, as `clipkernels._crossed` counts): all
    that `windingkernels.boundaries` reads where it cuts an outline to the box (its edges in
    the box, its winding at the corner by a ray in +x), a third of them on the bunny."""
    total = 0
    for b in range(start.shape[0] - 1):
        total += (start[b + 1] - start[b]) * (e_at[b + 1] - e_at[b])
    flat = np.empty((total, 2, 2))
    ids = np.empty((total, 2), np.int64)
    count, owner = np.empty(total, np.int64), np.empty(total, np.int64)
    g = 0
    for b in range(start.shape[0] - 1):
        for i in range(start[b], start[b + 1]):
            eye = seen_from(p, i, center, normal, axes)
            for e in range(e_at[b], e_at[b + 1]):
                t, a, z = e_tri[e], e_from[e], e_to[e]
                ax, ay = carried(corners, t, a, p, i, normal, axes, eye)
                bx, by = carried(corners, t, z, p, i, normal, axes, eye)
                up, down = _level(ay, by, box[1])
                if _apart(ax, ay, bx, by, box) and not (up or down):
                    continue
                flat[g, 0, 0], flat[g, 0, 1], flat[g, 1, 0], flat[g, 1, 1] = ax, ay, bx, by
                ids[g, 0], ids[g, 1] = welded[t, a], welded[t, z]
                count[g], owner[g] = e_cnt[e], i
                g += 1
    return flat[:g], ids[:g], count[:g], owner[:g]
