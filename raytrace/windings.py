"""A crowded pixel's shadow measured from its outline's winding numbers, with no polygon
boolean (`raytrace.exact_soft`), where the outline is seen to be noded.

The shadows of one pixel's triangles, each taken whole (`pyramid.uncut`) and turned counter-
clockwise, cover a point of the light's plane as many times as the winding number there of
the sum of their rings; an edge two of them run in opposite directions cancels from that
sum, so what is left (the outline: each edge between two welded corners with its net count)
has the same winding numbers.  The edges are split where two cross (float64, one crossing
point for both); every other two must lie apart or share a corner only (checked with a
margin: any doubt and the pixel takes `raytrace.arrange`'s union instead).  Then the winding
number is constant on each face the pieces bound, and a piece's right side is covered by its
count less than its left: the union's boundary is the pieces whose right side is covered 0
times (counted along a ray in +x from the first piece of one edge per run
of edges through corners with one edge in and one out, and carried along the run, adding the
count of each edge crossed).  The union's measures (area, Lambert's irradiance) are boundary
integrals: those of the fan of signed triangles from the light's centre over that boundary,
each clipped to the light's part seen from p (convex) (`raytrace.windmeasures`; in numba,
`raytrace.measurekernels`, where it loads).

A shadow that is not free (a triangle through p's parallel plane: the receiver's contact
with the occluder, where the whole shadow is unbounded) has no whole shadow to take.  Where a
pixel has up to LOOSE of them, the outline is its free shadows' alone, and those few are taken
away apart, cut to the pyramid (convex, `pyramid.cut`), by inclusion and exclusion over their
intersections (`raytrace.windmeasures`); a pixel with more, or with one whose corners do not
certainly turn one way (`windmeasures.turned`), takes `raytrace.arrange`'s union.

`split` measures a few thousand shadows' pixels in one pass of numpy (`boundaries`; `boundary`
is one pixel of it): a corner's id leads with its pixel, so every sort keeps a pixel's edges,
corners and pieces together in the order they take alone (the same floats, in the same
order, as the pixel alone), the pairs that may cross are sought and the ray's crossings
counted within a pixel only, the runs are followed by pointer jumping, and a doubt sets its
pixel's flag alone.  In numba (`raytrace.windingkernels`, the `fast` extra, where it loads)
`boundaries` takes one pixel at a time instead, the same chains and doubt byte for byte; this
numpy path stays for installs without it, and as its witness.
"""

from __future__ import annotations

import numpy as np

from . import arrange, polygons, pyramid

__all__ = ["boundaries", "boundary", "found", "groups", "split"]

# Doubt in the outline's orientation tests: a cross product within this much of the product of
# its two vectors' lengths (float64 roundings are ~1e-16 of it) counts as zero.
DOUBT = 2.0 ** -30
# Buckets of height an outline edge when its edges are sought that a level line crosses.
BUCKETS = 0.125
# Shadows `split` hands `boundaries` at once: whole pixels, about this many.
BATCH = 16384
# Outline edges `boundaries` nodes at once: whole pixels, about this many.
OUTLINE = 3072
# Shadows of a pixel that are not free (`split`) taken away apart, by inclusion and exclusion
# over their 2^LOOSE - 1 intersections (`windmeasures.measures`); a pixel with more is left to
# `raytrace.arrange`.
LOOSE = 4
# An outline is cut to the light's box grown by this much of its extent each way (`clip_box`):
# outside the light, yet away from its outline, where a mesh's edges crowd.
CLIP_MARGIN = 2.0 ** -6
# One empty chain (read only), held in an object array: `_kernel` sets it where a pixel has
# no piece.
_EMPTY = np.empty(1, object)
_EMPTY[0] = np.zeros((0, 2, 2))
_EMPTY[0].setflags(write=False)
# No whole clusters: their rims' (flat, ids, count, owner) empty.
NO_RIMS = (np.zeros((0, 2, 2)), np.zeros((0, 2), np.int64), np.zeros(0, np.int64),
           np.zeros(0, np.int64))


def boundary(uncut: np.ndarray, free: np.ndarray, ids: np.ndarray) -> np.ndarray | None:
    """The union's boundary (e, 2, 2) (each edge with the union on its left) of the whole
    shadows uncut (q, 3, 2) with welded corner ids (q, 3), or None where some shadow is not
    free (`pyramid.uncut`) or the outline is not certainly noded: `boundaries` of one pixel."""
    return boundaries(uncut, free, ids, np.zeros(len(uncut), np.int64), 1)[0]


def boundaries(uncut: np.ndarray, free: np.ndarray, ids: np.ndarray, owner: np.ndarray,
               n: int, rims: tuple | None = None, box: np.ndarray | None = None,
               partial: bool = False) -> np.ndarray:
    """(n,) object: the `boundary` of each of n pixels' shadows, all in one pass: the shadows
    uncut (q, 3, 2), free (q,), welded corner ids (q, 3) of the pixels owner (q,) (ascending,
    < n), and where given their whole clusters' rims (`wholekernels.rim_edges`: flat (e, 2,
    2), ids (e, 2), count (e,), owner (e,) ascending; in numba only).  A pixel's corners are
    told apart from another's by an id that leads with the pixel, so its edges, corners and
    pieces sort together, in the order they take alone; where its outline is in doubt, its
    boundary alone is None.  In numba, one pixel at a time, where it loads
    (`raytrace.windingkernels`: the same bytes); there, with `box` (x0, y0, x1, y1), each
    pixel's boundary inside that box only, closed along its sides where certain
    (`raytrace.clipkernels`: the same union inside the box); `partial`: the rims hold only
    what the cut to the box reads (`blockkernels.carried_edges`), so a pixel whose cut is in
    doubt is in doubt (None), not outlined whole."""
    loaded = polygons.kernels("windingkernels")
    if loaded is not None:
        return _kernel(loaded, uncut, free, ids, owner, n, NO_RIMS if rims is None else rims,
                       box, partial)
    if rims is not None and len(rims[3]):
        raise ValueError("whole clusters' rims need raytrace.windingkernels (numba)")
    chains, doubt = np.full(n, None, object), np.zeros(n, bool)
    doubt[owner[~free]] = True
    keep = ~doubt[owner]
    big = int(ids.max(initial=0)) + 1
    start, end, key_a, key_b = arrange.edges(uncut[keep], owner[keep, None] * big + ids[keep],
                                             np.ones(int(keep.sum()), bool))
    lo, hi = np.minimum(key_a, key_b), np.maximum(key_a, key_b)
    # by pixel, lower id, higher id: one key where it fits in an int64
    inv, first = _distinct(lo * big + hi % big) if n * big * big < 2 ** 63 else \
        _distinct(lo, hi)
    net = np.bincount(inv, np.where(key_a < key_b, 1.0, -1.0), len(first))
    use = np.flatnonzero(net != 0)
    f, up = first[use], net[use] > 0                   # up: the net runs from lo to hi
    low_first = (key_a[f] < key_b[f])[:, None]
    at_lo = np.where(low_first, start[f], end[f])
    at_hi = np.where(low_first, end[f], start[f])
    a = np.where(up[:, None], at_lo, at_hi)
    b = np.where(up[:, None], at_hi, at_lo)
    ia, ib = np.where(up, lo[f], hi[f]), np.where(up, hi[f], lo[f])
    count, group = np.abs(net[use]), lo[f] // big
    # the pixels in parts of about OUTLINE edges (a part's arrays stay in the caches)
    first = np.searchsorted(group, np.arange(n))
    parts = np.flatnonzero(np.r_[True, np.diff(first // OUTLINE) != 0]) if n else first
    for p0, p1 in zip(parts.tolist(), np.r_[parts[1:], n].tolist()):
        e = slice(first[p0], first[p1] if p1 < n else len(a))
        _settle(chains[p0:p1], doubt[p0:p1], a[e], b[e], ia[e], ib[e], count[e],
                group[e] - p0)
    return chains


def _kernel(loaded, uncut: np.ndarray, free: np.ndarray, ids: np.ndarray, owner: np.ndarray,
            n: int, rims: tuple, box: np.ndarray | None = None, partial: bool = False
            ) -> np.ndarray:
    """`boundaries` by `raytrace.windingkernels`."""
    doubt, at, pieces = loaded.boundaries(
        np.ascontiguousarray(uncut, np.float64), np.ascontiguousarray(free, bool),
        np.ascontiguousarray(ids, np.int64), np.ascontiguousarray(owner, np.int64), int(n),
        DOUBT, np.ascontiguousarray(rims[0], np.float64), np.ascontiguousarray(rims[1], np.int64),
        np.ascontiguousarray(rims[2], np.int64), np.ascontiguousarray(rims[3], np.int64),
        np.zeros(0) if box is None else np.asarray(box, np.float64), bool(partial))
    pieces = pieces.reshape(-1, 2, 2)
    chains = np.full(n, None, object)
    sure = np.flatnonzero(~doubt)
    some = at[sure + 1] > at[sure]
    # a pixel with no piece (most of a frame's: nothing in the box) shares one empty chain,
    # set at once, not sliced pixel by pixel
    chains[sure[~some]] = _EMPTY[np.zeros(int((~some).sum()), np.intp)]
    for k in sure[some].tolist():
        chains[k] = pieces[at[k]:at[k + 1]]
    return chains


def _settle(chains: np.ndarray, doubt: np.ndarray, a: np.ndarray, b: np.ndarray,
            ia: np.ndarray, ib: np.ndarray, count: np.ndarray, group: np.ndarray) -> None:
    """Fills chains (n,) object with the union's boundary of each pixel not in doubt (n,) (its
    pieces with no cover on their right) from the edges a-b (e, 2) of its outline with corner
    ids ia, ib and counts (e,), of the pixels group (e,) (ascending); sets doubt where that
    is not certain."""
    if len(a) == 0:
        for k in np.flatnonzero(~doubt).tolist():
            chains[k] = np.zeros((0, 2, 2))
        return
    corner = _distinct(np.r_[ia, ib])
    sa, sb, parent, jump = _pieces(a, b, ia, ib, count, group, doubt, corner[1])
    first = np.flatnonzero(np.r_[True, parent[1:] != parent[:-1]])     # one per edge, in order
    root, offset = _runs(corner[0], count, jump[np.r_[first[1:], len(parent)] - 1], group)
    runs = np.flatnonzero(root == np.arange(len(a)))
    at = first[runs]
    cover = _right_cover(sa[at], sb[at], parent[at], a, b, count, group, doubt)
    run = np.empty(len(a), np.int64)
    run[runs] = np.arange(len(runs))
    base = cover[run[root]] + offset
    # along an edge the cover changes only where another crosses it
    right = base[parent] + jump
    doubt[group[parent[right < 0]]] = True
    edge = np.flatnonzero(right == 0)
    edge = edge[~doubt[group[parent[edge]]]]
    sure = np.flatnonzero(~doubt)
    cuts = np.searchsorted(group[parent[edge]], sure)
    for k, chain in zip(sure.tolist(), np.split(np.stack([sa[edge], sb[edge]], axis=1),
                                                 cuts[1:])):
        chains[k] = chain


def _runs(corner: np.ndarray, count: np.ndarray, total: np.ndarray, group: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray]:
    """The edges from corner[:e] to corner[e:] (2e,) (numbered; no corner in two pixels) of
    the pixels group (e,) (ascending) with counts (e,) in runs through corners of one edge in
    and one out of equal counts (there the right sides of the two meet, so the second's first
    piece is covered as much as the first's last: by `total` (e,) more than its first piece):
    (the first edge of each edge's run (e,): the one with none before it, or the least of a
    closed run; how much more its first piece is covered than that edge's (e,)).  By pointer
    jumping: log2 of the most edges a pixel has steps over every edge at once."""
    va, vb = np.split(corner, 2)
    many = int(corner.max(initial=-1)) + 1
    out_deg = np.bincount(va, minlength=many)
    in_deg = np.bincount(vb, minlength=many)
    leaving = np.full(many, -1)
    leaving[va] = np.arange(len(va))
    succ = np.where((in_deg[vb] == 1) & (out_deg[vb] == 1), leaving[vb], -1)
    succ[(succ >= 0) & (count[np.maximum(succ, 0)] != count)] = -1
    pred = np.full(len(va), -1)
    pred[succ[succ >= 0]] = np.flatnonzero(succ >= 0)
    steps = int(np.bincount(group).max(initial=0)).bit_length()    # 2 ** steps > any run
    # the least edge within 2 ** k steps back (up: the edge 2 ** k back, -1 past a run's start)
    least, up = np.arange(len(va)), pred.copy()
    for _ in range(steps):
        on = np.flatnonzero(up >= 0)
        least[on] = np.minimum(least[on], least[up[on]])
        up[on] = up[up[on]]
    # a closed run (still a step back after 2 ** steps) starts at its least edge
    first = (pred < 0) | ((up >= 0) & (least == np.arange(len(va))))
    back = np.where(first, np.arange(len(va)), pred)
    offset = np.where(first, 0.0, total[np.maximum(pred, 0)])
    for _ in range(steps):
        offset = offset + offset[back]
        back = back[back]
    return back, offset


def _distinct(*keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct rows of the non-negative keys (k,) (the first most significant), numbered
    in their order: (the number of each row (k,), the index of each number's first row)."""
    order = np.argsort(keys[0]) if len(keys) == 1 else np.lexsort(keys[::-1])
    new = np.zeros(len(order), bool)
    for key in keys:
        new |= np.diff(key[order], prepend=-1) != 0
    number = np.empty(len(order), np.int64)
    number[order] = np.cumsum(new) - 1
    return number, (np.minimum.reduceat(order, np.flatnonzero(new)) if len(order) else order)


def _cross(u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """u x v and whether it is certainly nonzero (beyond DOUBT)."""
    return _turn(u[..., 0], u[..., 1], v[..., 0], v[..., 1])


def _turn(ux: np.ndarray, uy: np.ndarray, vx: np.ndarray, vy: np.ndarray,
          size: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """`_cross` of u, v given by their x and y (size: |ux| + |uy| where known)."""
    c = ux * vy - uy * vx
    size = np.abs(ux) + np.abs(uy) if size is None else size
    return c, np.abs(c) > DOUBT * (size * (np.abs(vx) + np.abs(vy)))


def _pieces(a: np.ndarray, b: np.ndarray, ia: np.ndarray, ib: np.ndarray, count: np.ndarray,
            group: np.ndarray, doubt: np.ndarray, at: np.ndarray):
    """The segments a-b (e, 2) with corner ids ia, ib (at: where each corner is first among
    ia then ib) and counts (e,) of the pixels group (e,) (ascending) split where two of a
    pixel cross (float64; one crossing point for both): (starts (s, 2), ends (s, 2), the edge
    of each (s,), in order along it, and how much more each piece's sides are covered than
    its edge's first piece's (s,): crossing another edge from its right to its left adds that
    edge's count); doubt (pixels,) set for a pixel unless every two of its edges certainly
    cross inside both, lie apart, or share a corner only."""
    spots, owner = np.r_[a, b][at], np.r_[group, group][at]
    order = np.lexsort((spots[:, 1], spots[:, 0], owner))
    spots, owner = spots[order], owner[order]
    same = (owner[1:] == owner[:-1]) & (spots[1:] == spots[:-1]).all(axis=1)
    doubt[owner[1:][same]] = True                    # two corners at one point
    i, j = _near(a, b, group)
    # seen from i's line first: the pairs whose j lies certainly on one side are apart
    ax, ay, bx, by = a[:, 0].copy(), a[:, 1].copy(), b[:, 0].copy(), b[:, 1].copy()
    dx, dy = bx - ax, by - ay
    size = np.abs(dx) + np.abs(dy)
    ux, uy, ui, x, y = dx[i], dy[i], size[i], ax[i], ay[i]
    ci, oi = _turn(ux, uy, ax[j] - x, ay[j] - y, ui)
    di, pi = _turn(ux, uy, bx[j] - x, by[j] - y, ui)
    rest = np.flatnonzero(~(oi & pi & (ci * di > 0)))
    i, j, ci, oi, di, pi = i[rest], j[rest], ci[rest], oi[rest], di[rest], pi[rest]
    ux, uy, uj, x, y = dx[j], dy[j], size[j], ax[j], ay[j]
    cj, oj = _turn(ux, uy, ax[i] - x, ay[i] - y, uj)
    dj, pj = _turn(ux, uy, bx[i] - x, by[i] - y, uj)
    shared = (ia[i] == ia[j]) | (ia[i] == ib[j]) | (ib[i] == ia[j]) | (ib[i] == ib[j])
    sure = oi & pi & oj & pj
    apart = oj & pj & (cj * dj > 0)
    cross = sure & (ci * di < 0) & (cj * dj < 0) & ~shared
    doubt[group[i[~(apart | cross | shared)]]] = True
    # a shared corner: the two edges leave it in certainly different directions
    s = np.flatnonzero(shared & ~apart)
    si, sj = i[s], j[s]
    at_a = (ia[si] == ia[sj]) | (ia[si] == ib[sj])     # the corner is i's start
    x, y = np.where(at_a, ax[si], bx[si]), np.where(at_a, ay[si], by[si])
    ux, uy = np.where(at_a, bx[si], ax[si]) - x, np.where(at_a, by[si], ay[si]) - y
    other_at_a = ia[sj] == np.where(at_a, ia[si], ib[si])
    vx, vy = np.where(other_at_a, bx[sj], ax[sj]) - x, np.where(other_at_a, by[sj], ay[sj]) - y
    _, turn = _turn(ux, uy, vx, vy)
    doubt[group[si[~(turn | (ux * vx + uy * vy < 0))]]] = True
    c = np.flatnonzero(cross)
    t_j = ci[c] / (ci[c] - di[c])                    # along edge j, from line i's side
    t_i = cj[c] / (cj[c] - dj[c])
    e, ic, jc = len(a), i[c], j[c]
    meet = np.stack([ax[jc] + t_j * dx[jc], ay[jc] + t_j * dy[jc]], axis=1)
    turn = np.sign(_turn(dx[jc], dy[jc], dx[ic], dy[ic])[0])    # i runs to j's left: +
    edge = np.r_[np.arange(e), np.arange(e), ic, jc]
    t = np.r_[np.zeros(e), np.ones(e), t_i, t_j]
    point = np.concatenate([a, b, meet, meet])
    change = np.r_[np.zeros(2 * e), turn * count[jc], -turn * count[ic]]
    order = _along(edge, t)
    edge, point, change = edge[order], point[order], np.cumsum(change[order])
    step = np.flatnonzero(edge[1:] == edge[:-1])
    start = np.flatnonzero(np.r_[True, edge[1:] != edge[:-1]])
    since = change - change[start][np.cumsum(np.r_[True, edge[1:] != edge[:-1]]) - 1]
    return point[step], point[step + 1], edge[step], since[step]


def _along(edge: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The order of points by edge (e,), then t (e,), then index (`np.lexsort`'s): a quick sort
    of t, then a stable one of the edges (a radix sort where their numbers are small), and
    np.lexsort itself where two points tie (none do but where three edges meet)."""
    order = np.argsort(t)
    small = edge[order].astype(np.min_scalar_type(int(edge.max(initial=0))))
    order = order[np.argsort(small, kind="stable")]
    e, s = edge[order], t[order]
    return np.lexsort((t, edge)) if ((e[1:] == e[:-1]) & (s[1:] == s[:-1])).any() else order


def _near(a: np.ndarray, b: np.ndarray, group: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pairs (i, j) of segments a-b (e, 2) of one pixel group (e,) (ascending) whose boxes
    meet (the others lie apart), each once: swept along x, pixel by pixel."""
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    order = np.lexsort((lo[:, 0], group))
    x, right, y0, y1 = lo[order, 0], hi[order, 0], lo[order, 1], hi[order, 1]
    # where each box's right end falls among its pixel's left ends after it (after the equal
    # ones): a binary search of them all at once
    g = group[order]
    end, top = np.arange(1, len(a) + 1), np.searchsorted(g, g, side="right")
    on = np.flatnonzero(end < top)
    while len(on):
        mid = (end[on] + top[on]) // 2
        left = x[mid] <= right[on]
        end[on] = np.where(left, mid + 1, end[on])
        top[on] = np.where(left, top[on], mid)
        on = on[end[on] < top[on]]
    many = end - np.arange(1, len(a) + 1)
    m = np.arange(int(many.sum())) + np.repeat(np.arange(1, len(a) + 1) - np.cumsum(many) + many,
                                               many)
    keep = np.flatnonzero((np.repeat(y0, many) <= y1[m]) & (y0[m] <= np.repeat(y1, many)))
    return order[np.searchsorted(np.cumsum(many), keep, side="right")], order[m[keep]]


def _right_cover(sa: np.ndarray, sb: np.ndarray, parent: np.ndarray, a: np.ndarray,
                 b: np.ndarray, count: np.ndarray, group: np.ndarray, doubt: np.ndarray
                 ) -> np.ndarray:
    """(s,) how many shadows cover the right side of each piece sa-sb (s, 2) of edge parent
    (s,) of the outline a-b (e, 2) with counts (e,), pixels group (e,) (ascending): the
    crossings of a ray in +x from a point just right of its midpoint (the ray meets an edge of
    its pixel that runs up where the point is left of it, +count, one that runs down where it
    is right of it, -count; the piece's own edge where it runs down); doubt (pixels,) set
    where a crossing is in doubt or a piece is level."""
    mid = (sa + sb) / 2
    mx, my = mid[:, 0].copy(), mid[:, 1].copy()
    ax, ay, bx, by = a[:, 0].copy(), a[:, 1].copy(), b[:, 0].copy(), b[:, 1].copy()
    r, f = _level(my, group[parent], np.minimum(ay, by), np.maximum(ay, by), group)
    fy, gy, y = ay[f], by[f], my[r]
    up = (fy <= y) & (gy > y)
    down = (gy <= y) & (fy > y)
    keep = np.flatnonzero((up | down) & (parent[r] != f))
    r, f, runs_up = r[keep], f[keep], up[keep]
    x, y = ax[f], ay[f]
    side, sure = _turn((bx - ax)[f], (by - ay)[f], mx[r] - x, my[r] - y)
    doubt[group[f[~sure]]] = True
    rise = sb[:, 1] - sa[:, 1]
    doubt[group[parent[~(np.abs(rise) > DOUBT * np.abs(sb - sa).sum(axis=1))]]] = True
    weight = np.where(runs_up & (side > 0), 1, 0) - np.where(~runs_up & (side < 0), 1, 0)
    wind = np.bincount(r, weight * count[f], len(sa))
    return wind - np.where(rise < 0, count[parent], 0)


def _level(y: np.ndarray, at: np.ndarray, low: np.ndarray, high: np.ndarray,
           group: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pairs (r, f) of heights y (m,) of pixels at (m,) and segments of the same pixel
    with heights low-high (e,) of pixels group (e,) (ascending), among them every pair with
    low <= y < high: each pixel's heights cut into BUCKETS buckets an edge, a segment in
    every bucket it meets (the bucket of a height is monotone in it: none is missed)."""
    n = int(max(group.max(initial=-1), at.max(initial=-1))) + 1
    bottom, top = np.full(n, np.inf), np.full(n, -np.inf)
    np.minimum.at(bottom, group, low)
    np.maximum.at(top, group, high)
    many = np.maximum(np.ceil(np.bincount(group, minlength=n) * BUCKETS), 1).astype(np.int64)
    scale = np.where(top > bottom, many / np.where(top > bottom, top - bottom, 1), 0)
    first = np.cumsum(many) - many

    def bucket(h, g):
        return first[g] + np.clip(np.floor((h - bottom[g]) * scale[g]), 0, many[g] - 1
                                  ).astype(np.int64)
    b0, b1 = bucket(low, group), bucket(high, group)
    span = b1 - b0 + 1
    edge = np.repeat(np.arange(len(low)), span)
    key = np.repeat(b0 - np.cumsum(span) + span, span) + np.arange(len(edge))
    order = np.argsort(key)                              # the pairs in any order
    key, edge = key[order], edge[order]
    q = bucket(y, at)
    lo, hi = np.searchsorted(key, q), np.searchsorted(key, q, side="right")
    r = np.repeat(np.arange(len(y)), hi - lo)
    f = edge[np.repeat(lo - np.cumsum(hi - lo) + hi - lo, hi - lo) + np.arange(len(r))]
    return r, f


def split(light, corners: np.ndarray, p: np.ndarray, pix: np.ndarray, tri: np.ndarray,
          heavy: np.ndarray, welded: np.ndarray, only: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray]:
    """The pairs `heavy` (indices into pix, tri) of the pixels `only` (bool, per pixel) whose
    union has a `boundary`: (chains (n,) object, the boundary or None per pixel; the pairs of
    the pixels with a boundary that are not in it: a pixel with up to LOOSE shadows that are
    not free (`pyramid.uncut`: a triangle through p's parallel plane, at a contact) has the
    boundary of its free ones' union, and those few are taken away apart, cut to the pyramid
    (`windmeasures.measures`))."""
    chains = np.full(len(p), None, object)
    mine = heavy[only[pix[heavy]]]
    mine = mine[np.argsort(pix[mine], kind="stable")]
    if len(mine) == 0:
        return chains, np.zeros(0, np.int64)
    flat, free = pyramid.uncut(light, corners, p, pix[mine], tri[mine])
    owner = np.cumsum(np.r_[True, pix[mine][1:] != pix[mine][:-1]]) - 1
    _batches(chains, flat, free, owner, mine, pix, tri, welded)
    # a few shadows that are not free: left out of the outline, kept apart (their pixels, in
    # doubt above, again without them)
    apart = ~free & (np.bincount(owner[~free], minlength=owner[-1] + 1) <= LOOSE)[owner]
    if apart.any():
        again = np.flatnonzero(np.isin(owner, owner[apart]) & ~apart)
        redo = np.cumsum(np.r_[True, owner[again][1:] != owner[again][:-1]]) - 1
        _batches(chains, flat[again], free[again], redo, mine[again], pix, tri, welded)
    apart = mine[apart]
    return chains, apart[found(chains)[pix[apart]]]


def _batches(chains: np.ndarray, flat: np.ndarray, free: np.ndarray, owner: np.ndarray,
             rows: np.ndarray, pix: np.ndarray, tri: np.ndarray, welded: np.ndarray) -> None:
    """chains[pix] = the `boundaries` of the whole shadows flat (q, 3, 2), free (q,) of the
    pairs rows (q,) of the pixels numbered owner (q,) (0, 1, ... in order), in batches of about
    BATCH shadows (whole pixels: a batch's arrays stay in the caches)."""
    starts = np.flatnonzero(np.r_[True, owner[1:] != owner[:-1]])
    batch = np.flatnonzero(np.r_[True, np.diff(starts // BATCH) != 0])
    for p0, p1 in zip(batch.tolist(), np.r_[batch[1:], len(starts)].tolist()):
        at = slice(starts[p0], starts[p1] if p1 < len(starts) else len(rows))
        chains[pix[rows[starts[p0:p1]]]] = boundaries(
            flat[at], free[at], welded[tri[rows[at]]], owner[at] - p0, p1 - p0)


def clip_box(light) -> np.ndarray:
    """(4,) x0, y0, x1, y1: the box `boundaries` cuts an outline to, the light's hull's box
    in its plane's coordinates grown by CLIP_MARGIN of its extent each way."""
    lo, hi = light.hull.min(axis=0), light.hull.max(axis=0)
    grow = CLIP_MARGIN * (hi - lo).max()
    return np.r_[lo - grow, hi + grow]


def groups(keys: np.ndarray, items: np.ndarray) -> tuple[list, list]:
    """The distinct keys (ascending, as given: the pixels of loose shadows) and the items
    (arrays) of each."""
    starts = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1]]) if len(keys) else keys
    return keys[starts].tolist(), np.split(items, starts[1:])


def found(chains: np.ndarray) -> np.ndarray:
    """(n,) bool: where chains (n,) object (`split`) holds a boundary."""
    return np.fromiter((c is not None for c in chains), bool, len(chains))
