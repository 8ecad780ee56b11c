"""A pixel's outline in numba (`raytrace.windingkernels`, `raytrace.blockkernels`): its
shadows' edges and any rims' (edges given with a count: `raytrace.blockwindings`) counted
by their welded corners, each undirected edge's net count, the edges in the order of their
corners' ids (`windings.boundaries`' numpy path: the same edges, counts and floats).
"""

from __future__ import annotations

import numpy as np

from .packetkernels import _jit

# Keys `_stable` orders by insertion (quadratic: a few only).  A pixel's outline cut to the
# light's box has 43 edges at the median on the bunny 128 x 128, 99 at the 3rd quartile, 164 at
# the 9th decile: up to 128 keys by insertion the winding kernel takes 0.965x the time it takes
# up to 64.
FEW = 128


@_jit(inline="always")
def _turn(ux, uy, vx, vy, size, margin):
    """`windings._turn` of scalars: u x v and whether it is certainly nonzero."""
    c = ux * vy - uy * vx
    return c, abs(c) > margin * (size * (abs(vx) + abs(vy)))


@_jit()
def _outline(uncut, ids, r0, r1, big, rims, e0, e1, box):
    """The outline of the shadows rows r0..r1 and the rims' edges e0..e1 (`arrange.edges`,
    then each undirected edge's net count, its first edge's corners): (ax, ay, bx, by (m,),
    corner ids ia, ib (m,), counts (m,)), the edges in the order of (lower id, higher id)
    (with a box: of their first edges); big: more than any id; box (4,) x0, y0, x1, y1: only
    the edges whose boxes meet it (an edge and the one it cancels have one box), or (0,):
    all."""
    rim, rim_ids, rim_count = rims
    rows = np.empty(r1 - r0, np.int64)
    v = 0
    for r in range(r0, r1):
        signed = (uncut[r, 1, 0] - uncut[r, 0, 0]) * (uncut[r, 2, 1] - uncut[r, 0, 1]) - \
            (uncut[r, 1, 1] - uncut[r, 0, 1]) * (uncut[r, 2, 0] - uncut[r, 0, 0])
        if signed != 0:
            rows[v] = r if signed > 0 else -1 - r
            v += 1
    many = 3 * v + e1 - e0
    row, s0, s1 = np.empty(many, np.int64), np.empty(many, np.int64), np.empty(many, np.int64)
    lo, hi, way = np.empty(many, np.int64), np.empty(many, np.int64), np.empty(many, np.int64)
    i, boxed = 0, box.shape[0] == 4
    for e in range(3):
        for w in range(v):
            r = rows[w]
            turn = r < 0
            r = -1 - r if turn else r
            a, b = ((e + 1) % 3, e) if turn else (e, (e + 1) % 3)
            if boxed and _apart(uncut[r, a, 0], uncut[r, a, 1], uncut[r, b, 0], uncut[r, b, 1],
                                box):
                continue
            row[i], s0[i], s1[i] = r, a, b
            ka, kb = ids[r, a], ids[r, b]
            lo[i], hi[i], way[i] = min(ka, kb), max(ka, kb), 1 if ka < kb else -1
            i += 1
    t = i
    for g in range(e0, e1):                  # a rim's edge: its own count, start to end
        if boxed and _apart(rim[g, 0, 0], rim[g, 0, 1], rim[g, 1, 0], rim[g, 1, 1], box):
            continue
        row[i], s0[i], s1[i] = g, 0, 1
        ka, kb = rim_ids[g, 0], rim_ids[g, 1]
        lo[i], hi[i] = min(ka, kb), max(ka, kb)
        way[i] = rim_count[g] if ka < kb else -rim_count[g]
        i += 1
    rep, net = _tally(lo[:i], hi[:i], way[:i])
    # in the order of their corners' ids, as numpy's path (`windings.boundaries`) has them;
    # cut to a box (the block path, which numpy has not), as they come: the order sets only
    # which of two edges a crossing is computed along and the chain's order, not the union
    order = np.arange(rep.shape[0]) if boxed else _order(lo[rep], hi[rep], big)
    m = order.shape[0]
    ax, ay, bx, by = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    ia, ib, cnt = np.empty(m, np.int64), np.empty(m, np.int64), np.empty(m, np.int64)
    for g in range(m):
        f, up = rep[order[g]], net[order[g]] > 0         # f: the first of the edge's edges
        r = row[f]
        c_lo, c_hi = (s0[f], s1[f]) if way[f] > 0 else (s1[f], s0[f])
        c_a, c_b = (c_lo, c_hi) if up else (c_hi, c_lo)
        if f < t:
            ax[g], ay[g], bx[g], by[g] = uncut[r, c_a, 0], uncut[r, c_a, 1], \
                uncut[r, c_b, 0], uncut[r, c_b, 1]
        else:
            ax[g], ay[g], bx[g], by[g] = rim[r, c_a, 0], rim[r, c_a, 1], rim[r, c_b, 0], \
                rim[r, c_b, 1]
        ia[g], ib[g] = (lo[f], hi[f]) if up else (hi[f], lo[f])
        cnt[g] = abs(net[order[g]])
    return ax, ay, bx, by, ia, ib, cnt


@_jit(inline="always")
def _level(ay, by, y):
    """(up, down): the edge from height ay to by crosses the level y going up (from at or
    below it to above) or going down (from above to at or below): the half-open rule by which
    a ray along y counts an edge once, however the edges' ends sit on it."""
    return ay <= y < by, by <= y < ay


@_jit(inline="always")
def _apart(ax, ay, bx, by, box):
    """Whether the box of the segment a-b misses the box x0, y0, x1, y1."""
    return min(ax, bx) > box[2] or max(ax, bx) < box[0] or min(ay, by) > box[3] or \
        max(ay, by) < box[1]


@_jit()
def _tally(lo, hi, way):
    """The undirected edges lo-hi (k,) (corner ids, >= 0) whose net count is not zero: (the
    first of each one's edges (u,), its net count (u,)), in the order of those first edges;
    an edge adds way (k,) (its count, + where it runs from its lower id), by a table of open
    addressing."""
    k = lo.shape[0]
    size = 16
    while size < 2 * k:
        size *= 2
    # one table (the slot's lower id, -1 where free; its higher id; its edge's number) and
    # one row of (first edge, net count): two allocations a call, not nine (it runs once a
    # block and once a pixel)
    table = np.empty((3, size), np.int64)
    table[0, :] = -1
    out = np.zeros((2, k), np.int64)
    u = 0
    for i in range(k):
        h = ((lo[i] * 73856093) ^ (hi[i] * 19349663)) & (size - 1)
        while table[0, h] >= 0 and (table[0, h] != lo[i] or table[1, h] != hi[i]):
            h = (h + 1) & (size - 1)
        if table[0, h] < 0:
            table[0, h], table[1, h], table[2, h] = lo[i], hi[i], u
            out[0, u] = i
            u += 1
        out[1, table[2, h]] += way[i]
    kept = 0
    for j in range(u):                                   # those whose net is not zero
        if out[1, j] != 0:
            out[0, kept], out[1, kept] = out[0, j], out[1, j]
            kept += 1
    return out[0, :kept], out[1, :kept]


@_jit()
def _order(lo, hi, big):
    """The order of the edges by lower corner id lo (k,), then higher hi (k,) (< big), then
    number (a stable sort): one sort of a key where it fits in an int64."""
    many = lo.shape[0]
    if many == 0:
        return np.empty(0, np.int64)
    if float(big) * float(big) >= 2.0 ** 62:
        order = _stable(hi)
        return order[_stable(lo[order])]
    key = np.empty(many, np.int64)
    for i in range(many):
        key[i] = lo[i] * big + hi[i]
    return _stable(key)


@_jit()
def _stable(key):
    """The order of key (k,) in a stable sort (np.argsort's, mergesort): up to FEW keys with
    no NaN by insertion (a winding kernel's outline: FEW's comment), else a quick sort, then
    each run of equal keys (NaNs one run) in order of place."""
    if key.shape[0] <= FEW:
        order, plain = np.empty(key.shape[0], np.int64), True
        for a in range(key.shape[0]):
            v, w = key[a], a
            if v != v:
                plain = False
                break
            while w > 0 and key[order[w - 1]] > v:
                order[w] = order[w - 1]
                w -= 1
            order[w] = a
        if plain:
            return order
    order = np.argsort(key)
    g = 0
    while g < key.shape[0]:
        h = g + 1
        while h < key.shape[0] and (key[order[h]] == key[order[g]] or (
                key[order[h]] != key[order[h]] and key[order[g]] != key[order[g]])):
            h += 1
        for a in range(g + 1, h):                        # insertion sort of the run
            i, w = order[a], a
            while w > g and order[w - 1] > i:
                order[w] = order[w - 1]
                w -= 1
            order[w] = i
        g = h
    return order
