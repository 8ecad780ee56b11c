"""The covers right of an outline's runs, in numba (`raytrace.windingkernels`: how many
shadows cover the right side of each run's first piece).  `covers` casts a ray in +x from
each run's first piece, as numpy's path does (`windings._right_cover`: the same doubt);
`covers_tied`, for an outline cut to a box (the block path, which numpy has not), casts one
only for a run whose cover no crossing ties to another's, nor a box's side.  The bunny
256x256's outlines have ~11 runs a pixel, ~5 of them so untied; the winding kernel ~0.95x.
"""

from __future__ import annotations

import numpy as np

from .outlinekernels import _level, _turn
from .packetkernels import _jit

# Rays (one a run of the outline) up to which `covers` passes each ray over every edge rather
# than over the edges in buckets of height (whose making costs more than a few rays).
FEW_RAYS = 8


@_jit()
def covers(pa, pb, first, root, ax, ay, bx, by, cnt, margin, sides):
    """(certain, the cover right of each run's first piece (m,), by its run's first edge) by
    a ray in +x from its midpoint, as `windings._right_cover`; not certain where a side is in
    doubt or the piece is level; 0 right of a box's side (edges from `sides` on: outside the
    box, `clipkernels.clipped`)."""
    m = ax.shape[0]
    cover = np.zeros(m, np.int64)
    rays = 0
    for e in range(min(m, sides)):
        rays += root[e] == e
    # a few rays pass every edge; more, the edges in buckets of height first (the same
    # edges tested: those whose span holds the ray's height)
    few = rays <= FEW_RAYS
    levels = _every() if few else _levels(ay, by)
    for e in range(min(m, sides)):
        if root[e] == e:
            ok, cover[e] = _ray(e, pa, pb, first, ax, ay, bx, by, cnt, margin, few, levels)
            if not ok:
                return False, cover
    return True, cover


@_jit(inline="always")
def _bucket(h, bottom, scale, many):
    """The bucket of height h (`_levels`)."""
    return min(max(int(np.floor((h - bottom) * scale)), 0), many - 1) if scale > 0 else 0


@_jit()
def _levels(ay, by):
    """The edges of heights ay-by (m,) in buckets of height: (where each bucket's edges start
    (b + 1,), the edges (k,), the least and most height, the buckets a unit of height); an
    edge in every bucket from its low end's to its high end's (a height's bucket is monotone
    in it: every edge whose span holds a height is in its bucket)."""
    m = ay.shape[0]
    bottom, top = min(ay.min(), by.min()), max(ay.max(), by.max())
    many = max(m // 4, 1)
    scale = many / (top - bottom) if top > bottom else 0.0
    if not np.isfinite(scale):
        scale = 0.0
    start = np.zeros(many + 1, np.int64)
    for f in range(m):
        b0 = _bucket(min(ay[f], by[f]), bottom, scale, many)
        b1 = _bucket(max(ay[f], by[f]), bottom, scale, many)
        for b in range(b0, b1 + 1):
            start[b + 1] += 1
    for b in range(many):
        start[b + 1] += start[b]
    fill, edge = start[:many].copy(), np.empty(start[many], np.int64)
    for f in range(m):
        b0 = _bucket(min(ay[f], by[f]), bottom, scale, many)
        for b in range(b0, _bucket(max(ay[f], by[f]), bottom, scale, many) + 1):
            edge[fill[b]] = f
            fill[b] += 1
    return start, edge, bottom, top, scale


@_jit()
def covers_tied(ent, pos, before, jump, root, offset, pa, pb, first, ax, ay, bx, by, cnt, margin,
            sides):
    """`covers`' covers (certain, (m,) by each run's first edge), a ray cast only for a run
    whose cover no crossing ties to another's: at a crossing of edges i and j (no third
    edge there: no tie along either), the covers right of each just before it differ by
    one's count, as the crossing's turn says (`_sweep`'s points: i's jump there is turn
    cnt[j], j's -turn cnt[i]); the runs so tied are grouped (a union-find, each run's cover
    kept as its group's first's and a difference), a group's cover is 0 where it holds a
    box's side, else its least run's ray; a difference the crossings do not agree on, in
    doubt."""
    m = ax.shape[0]
    up, less = np.arange(m), np.zeros(m, np.int64)   # cover[r] = cover[up[r]] + less[r]
    for g in range(2 * m, ent.shape[0], 2):
        if before[g] < 0 or before[g + 1] < 0:
            continue
        i, j = ent[g, 0], ent[g + 1, 0]
        # cover[root j] - cover[root i], from the covers right of each just before it
        d = -pos[g + 1, 3] if pos[g, 3] > 0 else pos[g, 3]
        step = offset[i] + jump[before[g]] + int(d) - offset[j] - jump[before[g + 1]]
        a, da = _top(root[i], up, less)
        b, db = _top(root[j], up, less)
        if a == b:
            if db != da + step:
                return False, less
            continue
        up[b], less[b] = a, da + step - db
    base = np.full(m, np.iinfo(np.int64).min)       # each group's first's cover, where known
    for e in range(sides, m):                       # a box's side: 0 right of it
        if root[e] == e:
            a, da = _top(e, up, less)
            if base[a] != np.iinfo(np.int64).min and base[a] != -da:
                return False, less
            base[a] = -da
    cover, every = np.zeros(m, np.int64), _every()
    for e in range(min(m, sides)):
        if root[e] != e:
            continue
        a, da = _top(e, up, less)
        if base[a] == np.iinfo(np.int64).min:
            ok, c = _ray(e, pa, pb, first, ax, ay, bx, by, cnt, margin, True, every)
            if not ok:
                return False, cover
            base[a] = c - da
        cover[e] = base[a] + da
    return True, cover


@_jit(inline="always")
def _top(r, up, less):
    """The first run of r's group and cover[r] less its cover; r and the runs on its way
    then point at that first run, with their differences to it (path compression)."""
    top, d = r, 0
    while up[top] != top:
        d += less[top]
        top = up[top]
    rest = d
    while up[r] != top and up[r] != r:
        nxt, step = up[r], less[r]
        up[r], less[r] = top, rest
        rest -= step
        r = nxt
    return top, d


@_jit()
def _ray(e, pa, pb, first, ax, ay, bx, by, cnt, margin, few, levels):
    """The cover right of the first piece of the run whose first edge is e, by a ray in +x
    from its midpoint (`covers`): (certain, the cover); few: the ray passes every edge, else
    only those of its height's bucket (levels: `_levels`' five)."""
    start, edge, bottom, top, scale = levels
    s = first[e]
    mx, my = (pa[s, 0] + pb[s, 0]) / 2, (pa[s, 1] + pb[s, 1]) / 2
    wind, g0, g1 = 0, 0, 0
    if few:
        g1 = ax.shape[0]
    elif bottom <= my <= top:                            # else no edge's span holds it
        b = _bucket(my, bottom, scale, start.shape[0] - 1)
        g0, g1 = start[b], start[b + 1]
    for g in range(g0, g1):
        f = g if few else edge[g]
        up, down = _level(ay[f], by[f], my)
        if f == e or not (up or down):
            continue
        ux, uy = bx[f] - ax[f], by[f] - ay[f]
        side, sure = _turn(ux, uy, mx - ax[f], my - ay[f], abs(ux) + abs(uy), margin)
        if not sure:
            return False, 0
        if up and side > 0:
            wind += cnt[f]
        elif down and side < 0:
            wind -= cnt[f]
    rise = pb[s, 1] - pa[s, 1]
    if not abs(rise) > margin * (abs(pb[s, 0] - pa[s, 0]) + abs(pb[s, 1] - pa[s, 1])):
        return False, 0
    return True, wind - (cnt[e] if rise < 0 else 0)


@_jit()
def _every():
    """`_levels`' five where a ray passes every edge (none used)."""
    return np.zeros(2, np.int64), np.zeros(0, np.int64), 0.0, 0.0, 0.0
