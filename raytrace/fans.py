"""Fans of triangles around a mesh's vertices, whose shadows the exact visibility unites as
one polygon each (`raytrace.exact_soft`).

A fan is the triangles around one vertex v of an object, each met once, consistently wound
(v, x_i, x_(i+1)): closed (around an inner vertex) or open (at a border).  Seen from p, where
every triangle of a fan is wholly inside the pyramid (uncut) and their shadows all turn the
same way about v's shadow v' with each angle at v' in (0, pi) and not degenerate, the shadows
are consecutive triangles about v' that do not overlap: a closed fan whose angles sum to
2 pi (not 4 pi, ...) covers exactly the star polygon x_0' .. x_(m-1)' around v', an open one
whose angles sum to less than 2 pi exactly the polygon v', x_0' .. x_m'.  Any other fan (cut,
a triangle missing: p's own, culled, outside, turned the other way, folded) is united
triangle by triangle, as is every triangle of no fan.  The union is the same region, its
corners the same float64 shadows of the same corners: only the pieces are fewer.

The fans are chosen once per scene, greedily, so that no triangle is in two (the most
corners first); a non-manifold vertex, a vertex whose triangles are wound both ways or
whose triangles make two cycles is no fan's centre.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

# A shadow triangle's angle at v' counts as turned one way when the sine of its angle there
# is at least this (float64 cross products of corners of order 1 are ~1e-16 off: far
# below); a nearly folded or edge-on fan is united triangle by triangle instead.
MIN_SINE = 1e-9


class Fans(NamedTuple):
    """Per scene triangle: its fan fan (M,) (-1: none), its place in that fan's order pos
    (M,) and which of its corners is the fan's centre apex (M,); per fan its size (F,) and
    whether it is closed (F,)."""

    fan: np.ndarray
    pos: np.ndarray
    apex: np.ndarray
    size: np.ndarray
    closed: np.ndarray


def fans(ids: np.ndarray, welded: np.ndarray, casts: np.ndarray | None = None) -> Fans:
    """The `Fans` of triangles of objects ids (M,) with welded corners (M, 3) (each corner's
    index among the distinct corners); `casts` (n_objects,) bool: only the objects that cast
    shadows get fans."""
    M = len(ids)
    fan, pos, apex = np.full(M, -1), np.zeros(M, np.int64), np.zeros(M, np.int64)
    size, closed = [], []
    for j in range(int(ids.max(initial=-1)) + 1):
        tris = np.flatnonzero(ids == j)
        if len(tris) < 2 or (casts is not None and not casts[j]):
            continue
        vid = np.unique(welded[tris].reshape(-1), return_inverse=True)[1].reshape(-1, 3)
        for v, chain, ring in _object_fans(vid):
            fan[tris[chain]] = len(size)
            pos[tris[chain]] = np.arange(len(chain))
            apex[tris[chain]] = (vid[chain] == v).argmax(axis=1)
            size.append(len(chain))
            closed.append(ring)
    return Fans(fan, pos, apex, np.array(size, np.int64), np.array(closed, bool))


def _object_fans(vid: np.ndarray):
    """(v, triangles in order, closed) of the fans chosen among triangles vid (F, 3) (welded
    corner indices)."""
    rot = [(vid[:, c], vid[:, (c + 1) % 3], vid[:, (c + 2) % 3]) for c in range(3)]
    v = np.concatenate([r[0] for r in rot])
    x = np.concatenate([r[1] for r in rot]).tolist()
    y = np.concatenate([r[2] for r in rot]).tolist()
    t = np.tile(np.arange(len(vid)), 3).tolist()
    order = np.argsort(v, kind="stable")
    starts = np.flatnonzero(np.r_[True, np.diff(v[order]) != 0])
    ends = np.r_[starts[1:], len(order)]
    # the most corners first
    by = np.argsort(-(ends - starts), kind="stable")
    order, starts, ends = order.tolist(), starts.tolist(), ends.tolist()
    taken = bytearray(len(vid))
    for k in by.tolist():
        own = order[starts[k]:ends[k]]
        if len(own) < 2 or any(taken[t[i]] for i in own):
            continue
        got = _chain({x[i]: (y[i], t[i]) for i in own}, len(own))
        if got is None:
            continue
        for i in own:
            taken[t[i]] = 1
        yield int(v[order[starts[k]]]), np.array(got[0]), got[1]


def _chain(nxt: dict, m: int):
    """The triangles of a fan in order around its centre from link edges x -> (y, triangle):
    (triangles, closed), or None where the edges do not make one cycle or one path."""
    if len(nxt) < m:
        return None                                   # a link corner starts two edges
    heads = set(nxt) - {y for y, _ in nxt.values()}
    if len(heads) > 1:
        return None
    at = next(iter(heads)) if heads else next(iter(nxt))
    first, out = at, []
    while at in nxt and len(out) <= m:
        at, tri = nxt[at]
        out.append(tri)
        if at == first:
            break
    if len(out) != m or (not heads and at != first):
        return None
    return out, not heads


def merge(shapely, fans: Fans, flat: np.ndarray, pix: np.ndarray, tri: np.ndarray,
          whole: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The shadows flat (q, k, 2) of triangles tri (q,) seen from pixels pix (q,) (whole
    (q,): uncut, so flat[:, :3] are its corners' shadows in its own order) with every fan
    that qualifies (module docstring) as one polygon: (polygons (g,), their pixels (g,), and
    (q,) bool: the pairs left to unite one by one)."""
    single = np.ones(len(tri), bool)
    at = np.flatnonzero(whole & (fans.fan[tri] >= 0))
    if len(at) == 0:
        return np.zeros(0, object), np.zeros(0, np.int64), single
    f = fans.fan[tri[at]]
    key = pix[at] * len(fans.size) + f
    order = np.lexsort((fans.pos[tri[at]], key))
    at, f, key = at[order], f[order], key[order]
    starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    group = np.cumsum(np.r_[True, key[1:] != key[:-1]]) - 1
    counts = np.diff(np.r_[starts, len(at)])
    # the corners of each shadow from the fan's centre: v', x_i', x_(i+1)'
    a = fans.apex[tri[at]]
    v0, x0, x1 = (flat[at, (a + s) % 3] for s in (0, 1, 2))
    e0, e1 = x0 - v0, x1 - v0
    cross = e0[:, 0] * e1[:, 1] - e0[:, 1] * e1[:, 0]
    dot = (e0 * e1).sum(axis=1)
    scale = np.linalg.norm(e0, axis=1) * np.linalg.norm(e1, axis=1)
    sign = np.where(cross >= MIN_SINE * scale, 1, np.where(cross <= -MIN_SINE * scale, -1, 0))
    angle = np.arctan2(np.abs(cross), dot)
    lo = np.minimum.reduceat(sign, starts)
    hi = np.maximum.reduceat(sign, starts)
    total = np.add.reduceat(angle, starts)
    fan = f[starts]
    closed = fans.closed[fan]
    ok = (counts == fans.size[fan]) & (lo == hi) & (lo != 0) & \
        np.where(closed, total < 3 * np.pi, total < 2 * np.pi * (1 - 1e-9))
    use = ok[group]
    single[at[use]] = False
    # the rings: a closed fan's x_i' in order; an open one's v', x_0' .. x_m'
    good = np.flatnonzero(ok)
    renum = np.full(len(ok), -1)
    renum[good] = np.arange(len(good))
    g = renum[group[use]]
    pts = [x0[use]]
    ring = [g]
    place = [fans.pos[tri[at[use]]].astype(np.float64)]
    last = starts[good] + counts[good] - 1
    opened = ~closed[good]
    pts += [v0[starts[good]][opened], x1[last][opened]]
    ring += [np.flatnonzero(opened), np.flatnonzero(opened)]
    place += [np.full(int(opened.sum()), -1.0), counts[good][opened].astype(np.float64)]
    pts, ring, place = np.concatenate(pts), np.concatenate(ring), np.concatenate(place)
    order = np.lexsort((place, ring))
    polys = shapely.polygons(shapely.linearrings(pts[order], indices=ring[order]))
    return np.asarray(polys, object), pix[at[starts[good]]], single
