"""`windings.boundaries` in numba (the `fast` extra), one pixel at a time, where numpy's
passes over a batch's edges, corners, pairs and pieces cost most of the time.  The same
chains and doubt as numpy's path, bit for bit: an outline edge is the first of its shadows'
edges (edge 0 of every shadow, then 1, then 2) between its two welded corners, the edges in
the order of their corners' ids; two edges whose boxes meet are tested as `windings._near`
orders them (i the first along x, then by number), with the same products; a crossing point
is computed along j; the points along an edge are in order of t, then as `windings._along`
ties them (its start, its end, the crossings where it is i by j's place along x, then where
it is j by i's); the ray right of a run's first piece meets every other edge of its pixel
(`windings._right_cover`, `coverkernels.covers`); counts are small integers, exact in
float64 and in int64 here.
tests/raytrace/test_winding_kernels.py holds the two to the same bytes.  A kernel indexes
scalars, not row views (each view costs a reference count), and hands its inlined tests
floats, not arrays: numba counts references to an array an inlined function reads under a
branch, on each call (docs/speed.md, "Reference counts").  Where a box is given (the
shared outlines of `raytrace.blockwindings`), each outline is cut to it first
(`raytrace.clipkernels`), its edges in the order they come, not sorted by ids (the winding
kernel 0.94x on the bunny 256x256's; the same union); the numpy path has no such cut.
"""

from __future__ import annotations

import numpy as np

from .clipkernels import clipped, survey
from .coverkernels import covers, covers_tied
from .outlinekernels import _outline, _stable, _turn
from .packetkernels import _jit

# Points along an edge nearer than this (in t) may lie there in the other order: a crossing's
# two turns c, d are certain (each rounded by ~4 ulps of its products, and at least DOUBT =
# 2^-30 of them: within 2^-21 of itself), so its t = |c| / (|c| + |d|) lies within 2^-22 of
# the float edges' own, two within 2^-21 of each other's.  Where two lie this near (8x that),
# or a third edge meets two at their crossing, the piece between may be misplaced, and no
# crossing there ties two runs' covers (`coverkernels.covers_tied`).
APART = 2.0 ** -18


@_jit()
def boundaries(uncut, free, ids, owner, n, margin, rim, rim_ids, rim_count, rim_owner, box,
               partial):
    """`windings.boundaries` of n pixels' shadows uncut (q, 3, 2), free (q,), welded corner
    ids (q, 3) of the pixels owner (q,) (ascending), and of their whole clusters' rims (rim
    (e, 2, 2) each edge's start and end, rim_ids (e, 2), rim_count (e,), rim_owner (e,)
    ascending: `wholekernels.rim_edges`): (doubt (n,), where each pixel's chain starts in the
    pieces (n + 1,), the pieces (4 s,): each start's x, y, end's x, y); margin:
    `windings.DOUBT`; box (4,) x0, y0, x1, y1: each outline cut to it where certain
    (`clipkernels.clipped`), or (0,): whole; partial: the rims hold only the edges that
    meet the box or cross the level of its first corner (`blockkernels.carried_edges`:
    all that the cut reads), so a pixel the cut leaves in doubt is in doubt, not outlined
    whole."""
    doubt = np.zeros(n, np.bool_)
    at = np.zeros(n + 1, np.int64)
    out = np.empty(4 * max(64, owner.shape[0]))
    # np.int64(0), not 0: a literal 0 would have numba compile each callee once more, for
    # Literal[int](0), while it types the loop
    size = r0 = e0 = np.int64(0)
    q, m = owner.shape[0], rim_owner.shape[0]
    big = max(ids.max() + 1 if q else 1, rim_ids.max() + 1 if m else 1)
    for k in range(n):
        r1, e1 = r0, e0
        while r1 < q and owner[r1] == k:
            r1 += 1
        while e1 < m and rim_owner[e1] == k:
            e1 += 1
        ok, sa, sb = _pixel(uncut, free, ids, r0, r1, big, margin, (rim, rim_ids, rim_count),
                            e0, e1, box, partial)
        r0, e0 = r1, e1
        if not ok:
            doubt[k] = True
        else:
            out = _put(out, size, sa, sb)
            size += sa.shape[0]
        at[k + 1] = size
    return doubt, at, out[:4 * size]


@_jit()
def _put(out, size, sa, sb):
    """The pieces sa-sb (c, 2) written into out (4 s,) after its first size, with more room
    where needed: out or its copy."""
    if 4 * (size + sa.shape[0]) > out.shape[0]:
        grown = np.empty(8 * (size + sa.shape[0]))
        for g in range(4 * size):
            grown[g] = out[g]
        out = grown
    for s in range(sa.shape[0]):
        g = 4 * (size + s)
        out[g], out[g + 1], out[g + 2], out[g + 3] = sa[s, 0], sa[s, 1], sb[s, 0], sb[s, 1]
    return out


@_jit()
def _pixel(uncut, free, ids, r0, r1, big, margin, rims, e0, e1, box, partial):
    """One pixel's shadows rows r0..r1 and rims' edges e0..e1: (certain, the chain's starts
    (c, 2), ends (c, 2)); partial: `boundaries`'."""
    none = np.empty((0, 2))
    for r in range(r0, r1):
        if not free[r]:
            return False, none, none
    whole = box[:0]
    if box.shape[0] == 4:
        meets, sure, wind = survey(uncut, r0, r1, rims, e0, e1, box, margin)
        if sure and not meets and wind == 0:     # nothing in the box
            return True, none, none
        if sure and not meets and wind > 0:      # the box covered: its sides
            sa, sb = np.empty((4, 2)), np.empty((4, 2))
            for k in range(4):
                sa[k, 0], sa[k, 1] = box[(0, 2, 2, 0)[k]], box[(1, 1, 3, 3)[k]]
                sb[k, 0], sb[k, 1] = box[(2, 2, 0, 0)[k]], box[(1, 3, 3, 1)[k]]
            return True, sa, sb
        if sure and meets:                       # the edges that meet the box, cut to it
            ax, ay, bx, by, ia, ib, cnt = _outline(uncut, ids, r0, r1, big, rims, e0, e1, box)
            ok, cax, cay, cbx, cby, cia, cib, ccnt, cut = clipped(ax, ay, bx, by, ia, ib, cnt,
                                                                   box, big, margin, wind)
            if ok:
                return _noded(cax, cay, cbx, cby, cia, cib, ccnt, margin, cut, True)
    if partial:                                  # in doubt there, with the box's edges only
        return False, none, none
    # the whole outline (no box, or in doubt there)
    ax, ay, bx, by, ia, ib, cnt = _outline(uncut, ids, r0, r1, big, rims, e0, e1, whole)
    return _noded(ax, ay, bx, by, ia, ib, cnt, margin, ax.shape[0], False)


@_jit()
def _noded(ax, ay, bx, by, ia, ib, cnt, margin, sides, spread):
    """The chain of the outline a -> b (m,) with corner ids ia, ib and counts cnt (m,), a
    box's sides from `sides` on (0 cover right of them): (certain, starts (c, 2), ends (c,
    2)); spread: the runs' covers tied by their crossings (`coverkernels.covers_tied`, an
    outline cut to a box), else a ray each (`coverkernels.covers`, numpy's)."""
    none = np.empty((0, 2))
    m = ax.shape[0]
    if m == 0:
        return True, none, none
    ok, va, vb = _corners(ax, ay, bx, by, ia, ib)
    if not ok:
        return False, none, none
    ok, ent, pos = _crossings(ax, ay, bx, by, ia, ib, cnt, margin, sides)
    if not ok:
        return False, none, none
    pa, pb, parent, jump, first, before = _pieces(ent, pos, m)
    total = np.empty(m, np.int64)
    for e in range(m):
        total[e] = jump[first[e + 1] - 1]
    root, offset = _runs(va, vb, cnt, total)
    if spread:
        ok, cover = covers_tied(ent, pos, before, jump, root, offset, pa, pb, first, ax, ay,
                                bx, by, cnt, margin, sides)
    else:
        ok, cover = covers(pa, pb, first, root, ax, ay, bx, by, cnt, margin, sides)
    if not ok:
        return False, none, none
    sa, sb, c = np.empty((parent.shape[0], 2)), np.empty((parent.shape[0], 2)), 0
    for s in range(parent.shape[0]):                     # the pieces with no cover right
        e = parent[s]
        right = cover[root[e]] + offset[e] + jump[s]
        if right < 0:
            return False, none, none
        if right == 0:
            sa[c, 0], sa[c, 1], sb[c, 0], sb[c, 1] = pa[s, 0], pa[s, 1], pb[s, 0], pb[s, 1]
            c += 1
    return True, sa[:c], sb[:c]


@_jit()
def _corners(ax, ay, bx, by, ia, ib):
    """The corners of the outline numbered (va, vb (m,)), and whether no two of them lie at
    one point (each at its first place among the edges' starts, then ends), by two tables of
    open addressing (ids, then points: x and y equal as floats); the numbers are the corners'
    order of first place (any one-to-one numbering serves `_runs`)."""
    m = ax.shape[0]
    size = 16
    while size < 4 * m:
        size *= 2
    mask = size - 1
    slot = np.full(size, -1, np.int64)                   # the id held (ids are >= 0)
    at = np.empty(size, np.int64)
    number = np.empty(2 * m, np.int64)
    xs, ys = np.empty(2 * m), np.empty(2 * m)
    c = 0
    for i in range(2 * m):
        key = ia[i] if i < m else ib[i - m]
        h = _mixed(key, 0) & mask
        while slot[h] >= 0 and slot[h] != key:
            h = (h + 1) & mask
        if slot[h] < 0:
            slot[h], at[h] = key, c
            # + 0.0: -0.0 as 0.0, which == holds equal
            xs[c], ys[c] = ((ax[i], ay[i]) if i < m else (bx[i - m], by[i - m]))
            xs[c], ys[c] = xs[c] + 0.0, ys[c] + 0.0
            c += 1
        number[i] = at[h]
    bits_x, bits_y = xs[:c].view(np.int64), ys[:c].view(np.int64)
    slot[:] = -1
    for g in range(c):
        h = _mixed(bits_x[g], bits_y[g]) & mask
        while slot[h] >= 0:
            f = slot[h]
            if xs[f] == xs[g] and ys[f] == ys[g]:
                return False, number[:m], number[m:]
            h = (h + 1) & mask
        slot[h] = g
    return True, number[:m], number[m:]


@_jit(inline="always")
def _mixed(a, b):
    """A hash of the int64s a, b: MurmurHash3's finalizer of a line of them (products wrap;
    every bit of each reaches the low bits)."""
    v = a * -7046029254386353131 + b
    v ^= v >> 33
    v *= -49064778989728563
    v ^= v >> 33
    v *= -4265267296055464877
    return v ^ (v >> 33)


@_jit()
def _crossings(ax, ay, bx, by, ia, ib, cnt, margin, sides):
    """The points along the outline's edges (`windings._pieces`): (certain, entries (k, 2):
    each point's edge and its place among the ties, points (k, 4): t along the edge, x, y,
    the cover it adds); every pair whose boxes meet (swept along x, as `windings._near`)
    certainly crosses inside both, lies apart or shares a corner only.  Only the edges before
    `sides` are swept: from there on a box's sides (`clipkernels.clipped`), which meet no
    edge but at a corner they share (the cut edges end on them, the others lie inside the
    box by more than the cut's margin, or the cut was in doubt), 28 % of the sweep's tests
    on the bunny 256x256; the places of the points the same order."""
    m, n = ax.shape[0], sides
    ent, pos = np.empty((4 * m, 2), np.int64), np.zeros((4 * m, 4))
    for e in range(m):
        ent[e, 0], ent[e, 1], ent[m + e, 0], ent[m + e, 1] = e, 0, e, 1
        pos[e, 0], pos[e, 1], pos[e, 2] = 0.0, ax[e], ay[e]
        pos[m + e, 0], pos[m + e, 1], pos[m + e, 2] = 1.0, bx[e], by[e]
    left = np.empty(n)
    for e in range(n):
        left[e] = min(ax[e], bx[e])
    order = _stable(left)
    box = np.empty((4, n))                               # along the sweep
    for p in range(n):
        e = order[p]
        box[0, p], box[1, p] = left[e], max(ax[e], bx[e])
        box[2, p], box[3, p] = min(ay[e], by[e]), max(ay[e], by[e])
    k, p, q = 2 * m, np.int64(0), np.int64(1)     # not literals (`boundaries`)
    while True:                 # the sweep, resumed where its room ran out (room made here:
        state, k, p, q = _sweep(order, box, ax, ay, bx, by, ia, ib, cnt, margin, ent, pos,
                                k, p, q)                 # arrays set anew in its loop cost
        if state < 0:                                    # a reference count an access)
            return False, ent, pos
        if state == 0:
            return True, ent[:k], pos[:k]
        ent, pos = _grown(ent, pos, k)


@_jit()
def _sweep(order, box, ax, ay, bx, by, ia, ib, cnt, margin, ent, pos, k, p0, q0):
    """`_crossings`' sweep from the pair of places p0, q0 along it, its points from row k on:
    (0 where done, -1 where in doubt, 1 where out of room; the rows filled, the next pair)."""
    m = order.shape[0]
    for p in range(p0, m):
        right, bottom, top = box[1, p], box[2, p], box[3, p]
        for q in range(q0 if p == p0 else p + 1, m):
            if box[0, q] > right:
                break
            if not (bottom <= box[3, q] and box[2, q] <= top):
                continue
            i, j = order[p], order[q]
            state, t_i, t_j, x, y, turn = _pair(ax[i], ay[i], bx[i], by[i], ia[i], ib[i], ax[j],
                                                ay[j], bx[j], by[j], ia[j], ib[j], margin)
            if state < 0:
                return -1, k, p, q
            if state == 0:
                continue
            if k + 2 > ent.shape[0]:
                return 1, k, p, q
            ent[k, 0], ent[k, 1], ent[k + 1, 0], ent[k + 1, 1] = i, 2 + q, j, 2 + m + p
            pos[k, 0], pos[k, 1], pos[k, 2], pos[k, 3] = t_i, x, y, turn * cnt[j]
            pos[k + 1, 0], pos[k + 1, 1], pos[k + 1, 2] = t_j, x, y
            pos[k + 1, 3] = -turn * cnt[i]
            k += 2
    return 0, k, m, m


@_jit()
def _grown(ent, pos, k):
    """ent, pos with twice the room, their first k rows kept."""
    e, p = np.zeros((2 * ent.shape[0], 2), np.int64), np.zeros((2 * ent.shape[0], 4))
    for g in range(k):
        e[g, 0], e[g, 1] = ent[g, 0], ent[g, 1]
        p[g, 0], p[g, 1], p[g, 2], p[g, 3] = pos[g, 0], pos[g, 1], pos[g, 2], pos[g, 3]
    return e, p


@_jit(inline="always")
def _pair(axi, ayi, bxi, byi, iai, ibi, axj, ayj, bxj, byj, iaj, ibj, margin):
    """Edges i, j (starts, ends, corner ids) whose boxes meet (i first along x): (1 where they
    cross, with t along i, t along j, the crossing point x, y and the sign of j x i; 0 where
    they lie apart or share a corner, certainly; -1 where in doubt), with `windings._pieces`'s
    products.  Scalars, not the outline's arrays: numba counts references to an array passed
    to an inlined function with branches, on each call (4x the time of the test itself).
    Two edges that share a corner at one point (the same floats in both: the outline's two
    edges at each of its corners) turn exactly 0 there, so the four turns below decide
    nothing and only `_corner`'s test does: it is taken first."""
    shared = iai == iaj or iai == ibj or ibi == iaj or ibi == ibj
    corner, one = 0, False
    if shared:
        corner, one = _corner(axi, ayi, bxi, byi, iai, ibi, axj, ayj, bxj, byj, iaj, ibj,
                              margin)
        if one:
            return corner, 0.0, 0.0, 0.0, 0.0, 0.0
    dxi, dyi, dxj, dyj = bxi - axi, byi - ayi, bxj - axj, byj - ayj
    si, sj = abs(dxi) + abs(dyi), abs(dxj) + abs(dyj)
    ci, oi = _turn(dxi, dyi, axj - axi, ayj - ayi, si, margin)
    di, pi = _turn(dxi, dyi, bxj - axi, byj - ayi, si, margin)
    if oi and pi and ci * di > 0:
        return 0, 0.0, 0.0, 0.0, 0.0, 0.0
    cj, oj = _turn(dxj, dyj, axi - axj, ayi - ayj, sj, margin)
    dj, pj = _turn(dxj, dyj, bxi - axj, byi - ayj, sj, margin)
    apart = oj and pj and cj * dj > 0
    cross = oi and pi and oj and pj and ci * di < 0 and cj * dj < 0 and not shared
    if not (apart or cross or shared):
        return -1, 0.0, 0.0, 0.0, 0.0, 0.0
    if shared and not apart and corner < 0:
        return -1, 0.0, 0.0, 0.0, 0.0, 0.0
    if not cross:
        return 0, 0.0, 0.0, 0.0, 0.0, 0.0
    t_j, t_i = ci / (ci - di), cj / (cj - dj)
    x, y = axj + t_j * dxj, ayj + t_j * dyj
    turn = np.sign(dxj * dyi - dyj * dxi)
    return 1, t_i, t_j, x, y, turn


@_jit(inline="always")
def _corner(axi, ayi, bxi, byi, iai, ibi, axj, ayj, bxj, byj, iaj, ibj, margin):
    """Edges i, j sharing a corner id: (-1 where their other ends turn from it by too little
    to tell (collinear, the same way: they may overlap), else 0; whether j's copy of the
    corner is i's, the same floats)."""
    at_a = iai == iaj or iai == ibj                      # the corner is i's start
    x, y = (axi, ayi) if at_a else (bxi, byi)
    ux, uy = ((bxi, byi) if at_a else (axi, ayi))
    ux, uy = ux - x, uy - y
    other_at_a = iaj == (iai if at_a else ibi)
    wx, wy = (axj, ayj) if other_at_a else (bxj, byj)
    vx, vy = ((bxj, byj) if other_at_a else (axj, ayj))
    vx, vy = vx - x, vy - y
    _, sure = _turn(ux, uy, vx, vy, abs(ux) + abs(uy), margin)
    return (0 if sure or ux * vx + uy * vy < 0 else -1), wx == x and wy == y


@_jit()
def _pieces(ent, pos, m):
    """The edges' points (`_crossings`) in order along each edge (by t, then place) and the
    pieces between: (starts (s, 2), ends (s, 2), edges (s,), how much more each piece's
    sides are covered than its edge's first piece's (s,), where each edge's pieces start
    (m + 1,), the piece that ends at each point (k,): -1 where another lies within APART)."""
    k = ent.shape[0]
    start = np.zeros(m + 1, np.int64)
    for g in range(k):
        start[ent[g, 0] + 1] += 1
    for e in range(m):
        start[e + 1] += start[e]
    fill, idx = start[:m].copy(), np.empty(k, np.int64)
    for g in range(k):
        e = ent[g, 0]
        idx[fill[e]] = g
        fill[e] += 1
    for e in range(m):                                   # insertion sort by (t, place)
        for h in range(start[e] + 1, start[e + 1]):
            g, w = idx[h], h
            while w > start[e] and (pos[idx[w - 1], 0] > pos[g, 0] or (
                    pos[idx[w - 1], 0] == pos[g, 0] and ent[idx[w - 1], 1] > ent[g, 1])):
                idx[w] = idx[w - 1]
                w -= 1
            idx[w] = g
    s = k - m
    pa, pb = np.empty((s, 2)), np.empty((s, 2))
    parent, jump, first = np.empty(s, np.int64), np.empty(s, np.int64), np.empty(m + 1, np.int64)
    before = np.full(k, -1, np.int64)
    c = 0
    for e in range(m):
        first[e] = c
        run = 0.0
        for h in range(start[e], start[e + 1] - 1):
            g, f = idx[h], idx[h + 1]
            if h > start[e]:
                run += pos[g, 3]
            pa[c, 0], pa[c, 1], pb[c, 0], pb[c, 1] = pos[g, 1], pos[g, 2], pos[f, 1], pos[f, 2]
            parent[c], jump[c] = e, int(run)
            before[f] = c
            if pos[f, 0] - pos[g, 0] <= APART:       # maybe in the other order: not tied
                before[f] = before[g] = -1
            c += 1
    first[m] = c
    return pa, pb, parent, jump, first, before


@_jit()
def _runs(va, vb, cnt, total):
    """`windings._runs` of one pixel: (the first edge of each edge's run (m,), how much more
    its first piece is covered than that edge's (m,)), by walking each run once."""
    m = va.shape[0]
    many = max(va.max(), vb.max()) + 1
    out_deg, in_deg = np.zeros(many, np.int64), np.zeros(many, np.int64)
    leaving = np.full(many, -1, np.int64)
    for e in range(m):
        out_deg[va[e]] += 1
        in_deg[vb[e]] += 1
        leaving[va[e]] = e
    succ, pred = np.full(m, -1, np.int64), np.full(m, -1, np.int64)
    for e in range(m):
        v = vb[e]
        if in_deg[v] == 1 and out_deg[v] == 1 and cnt[leaving[v]] == cnt[e]:
            succ[e] = leaving[v]
            pred[leaving[v]] = e
    root, offset = np.full(m, -1, np.int64), np.zeros(m, np.int64)
    for g in range(2 * m):          # the open runs from their first edge, then each closed
        start = g % m               # one from its least
        if root[start] >= 0 or (g < m and pred[start] >= 0):
            continue
        e, at = start, 0
        while e >= 0 and root[e] < 0:
            root[e], offset[e] = start, at
            at += total[e]
            e = succ[e]
    return root, offset
