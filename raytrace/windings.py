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
each clipped to the light's part seen from p (convex) in numpy (`regions.inside`).
"""

from __future__ import annotations

import numpy as np

from . import arrange, pyramid
from .regions import closed_rings, inside, ring_measures

__all__ = ["boundary", "found", "measures", "split"]

# Doubt in the outline's orientation tests: a cross product within this much of the product of
# its two vectors' lengths (float64 roundings are ~1e-16 of it) counts as zero.
DOUBT = 2.0 ** -30


def boundary(uncut: np.ndarray, free: np.ndarray, ids: np.ndarray) -> np.ndarray | None:
    """The union's boundary (e, 2, 2) (each edge with the union on its left) of the whole
    shadows uncut (q, 3, 2) with welded corner ids (q, 3), or None where some shadow is not
    free (`pyramid.uncut`) or the outline is not certainly noded."""
    if not free.all():
        return None
    start, end, key_a, key_b = arrange.edges(uncut, ids, np.ones(len(uncut), bool))
    lo, hi = np.minimum(key_a, key_b), np.maximum(key_a, key_b)
    big = int(hi.max(initial=0)) + 1
    keys, first, inv = np.unique(lo * big + hi, return_index=True, return_inverse=True)
    net = np.bincount(inv.reshape(-1), np.where(key_a < key_b, 1.0, -1.0), len(keys))
    use = np.flatnonzero(net != 0)
    if len(use) == 0:
        return np.zeros((0, 2, 2))
    f, up = first[use], net[use] > 0                   # up: the net runs from lo to hi
    low_first = (key_a[f] < key_b[f])[:, None]
    at_lo = np.where(low_first, start[f], end[f])
    at_hi = np.where(low_first, end[f], start[f])
    a = np.where(up[:, None], at_lo, at_hi)
    b = np.where(up[:, None], at_hi, at_lo)
    ia, ib = np.where(up, lo[f], hi[f]), np.where(up, hi[f], lo[f])
    count = np.abs(net[use])
    pieces = _pieces(a, b, ia, ib, count)
    if pieces is None:
        return None
    sa, sb, parent, jump = pieces
    first = np.flatnonzero(np.r_[True, parent[1:] != parent[:-1]])     # one per edge, in order
    walk, root, offset = _runs(ia, ib, count, jump[np.r_[first[1:], len(parent)] - 1])
    at = first[walk[np.r_[True, root[1:] != root[:-1]]]]
    cover = _right_cover(sa[at], sb[at], parent[at], a, b, count)
    if cover is None:
        return None
    base = np.empty(len(a))
    base[walk] = cover[root] + offset
    # along an edge the cover changes only where another crosses it
    right = base[parent] + jump
    if (right < 0).any():
        return None
    edge = right == 0
    return np.stack([sa[edge], sb[edge]], axis=1)


def _runs(ia: np.ndarray, ib: np.ndarray, count: np.ndarray, total: np.ndarray):
    """The edges ia-ib (e,) with counts (e,) in runs through corners of one edge in and one
    out of equal counts (there the right sides of the two meet, so the second's first piece
    is covered as much as the first's last: by `total` (e,) more than its first piece):
    (the edges in run order (e,), the run of each (e,), how much more its first piece is
    covered than its run's first edge's (e,))."""
    corner, inv = np.unique(np.r_[ia, ib], return_inverse=True)
    va, vb = inv[:len(ia)], inv[len(ia):]
    out_deg = np.bincount(va, minlength=len(corner))
    in_deg = np.bincount(vb, minlength=len(corner))
    leaving = np.full(len(corner), -1)
    leaving[va] = np.arange(len(ia))
    succ = np.where((in_deg[vb] == 1) & (out_deg[vb] == 1), leaving[vb], -1)
    succ[(succ >= 0) & (count[np.maximum(succ, 0)] != count)] = -1
    has_pred = np.zeros(len(ia), bool)
    has_pred[succ[succ >= 0]] = True
    nxt, seen, walk, root = succ.tolist(), [False] * len(ia), [], []
    # runs from an edge with none before it, then the closed ones
    for s in np.flatnonzero(~has_pred).tolist() + list(range(len(ia))):
        e, r = s, (root[-1] + 1 if root else 0)
        while e >= 0 and not seen[e]:
            seen[e] = True
            walk.append(e)
            root.append(r)
            e = nxt[e]
    walk, root = np.array(walk, np.int64), np.array(root, np.int64)
    step = np.r_[0.0, total[walk][:-1]]
    run_start = np.flatnonzero(np.r_[True, root[1:] != root[:-1]])
    acc = np.cumsum(step)
    offset = acc - acc[run_start][root]
    return walk, root, offset


def _cross(u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """u x v and whether it is certainly nonzero (beyond DOUBT)."""
    c = u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]
    scale = (np.abs(u[..., 0]) + np.abs(u[..., 1])) * (np.abs(v[..., 0]) + np.abs(v[..., 1]))
    return c, np.abs(c) > DOUBT * scale


def _pieces(a: np.ndarray, b: np.ndarray, ia: np.ndarray, ib: np.ndarray, count: np.ndarray):
    """The segments a-b (e, 2) with corner ids ia, ib and counts (e,) split where two cross
    (float64; one crossing point for both): (starts (s, 2), ends (s, 2), the edge of each
    (s,), in order along it, and how much more each piece's sides are covered than its
    edge's first piece's (s,): crossing another edge from its right to its left adds that
    edge's count); None unless every two certainly cross inside both, lie apart, or share a
    corner only."""
    ids, at = np.unique(np.r_[ia, ib], return_index=True)
    spots = np.r_[a, b][at]
    if len(np.unique(spots[:, 0] + 1j * spots[:, 1])) != len(ids):
        return None                                  # two corners at one point
    i, j = _near(a, b)
    shared = (ia[i] == ia[j]) | (ia[i] == ib[j]) | (ib[i] == ia[j]) | (ib[i] == ib[j])
    ci, oi = _cross(b[i] - a[i], a[j] - a[i])
    di, pi = _cross(b[i] - a[i], b[j] - a[i])
    cj, oj = _cross(b[j] - a[j], a[i] - a[j])
    dj, pj = _cross(b[j] - a[j], b[i] - a[j])
    sure = oi & pi & oj & pj
    apart = (oi & pi & (ci * di > 0)) | (oj & pj & (cj * dj > 0))
    cross = sure & (ci * di < 0) & (cj * dj < 0) & ~shared
    if not (apart | cross | shared).all():
        return None
    # a shared corner: the two edges leave it in certainly different directions
    s = np.flatnonzero(shared & ~apart)
    at_i = np.where((ia[i[s]] == ia[j[s]]) | (ia[i[s]] == ib[j[s]]), 0, 1)
    corner = np.where(at_i[:, None] == 0, a[i[s]], b[i[s]])
    u = np.where(at_i[:, None] == 0, b[i[s]], a[i[s]]) - corner
    other_at_a = ia[j[s]] == np.where(at_i == 0, ia[i[s]], ib[i[s]])
    v = np.where(other_at_a[:, None], b[j[s]], a[j[s]]) - corner
    _, turn = _cross(u, v)
    if not (turn | ((u * v).sum(axis=1) < 0)).all():
        return None
    c = np.flatnonzero(cross)
    t_j = ci[c] / (ci[c] - di[c])                    # along edge j, from line i's side
    t_i = cj[c] / (cj[c] - dj[c])
    meet = a[j[c]] + t_j[:, None] * (b[j[c]] - a[j[c]])
    e, ic, jc = len(a), i[c], j[c]
    turn = np.sign(_cross(b[jc] - a[jc], b[ic] - a[ic])[0])    # i runs to j's left: +
    edge = np.r_[np.arange(e), np.arange(e), ic, jc]
    t = np.r_[np.zeros(e), np.ones(e), t_i, t_j]
    point = np.concatenate([a, b, meet, meet])
    change = np.r_[np.zeros(2 * e), turn * count[jc], -turn * count[ic]]
    order = np.lexsort((t, edge))
    edge, point, change = edge[order], point[order], np.cumsum(change[order])
    step = np.flatnonzero(edge[1:] == edge[:-1])
    start = np.flatnonzero(np.r_[True, edge[1:] != edge[:-1]])
    since = change - change[start][np.cumsum(np.r_[True, edge[1:] != edge[:-1]]) - 1]
    return point[step], point[step + 1], edge[step], since[step]


def _near(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pairs (i, j) of segments a-b (e, 2) whose boxes meet (the others lie apart), each
    once: swept along x."""
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    order = np.argsort(lo[:, 0], kind="stable")
    end = np.searchsorted(lo[order, 0], hi[order, 0], side="right")
    many = np.maximum(end - np.arange(len(a)) - 1, 0)
    k = np.repeat(np.arange(len(a)), many)
    i = order[k]
    j = order[k + 1 + np.arange(len(k)) - np.repeat(np.cumsum(many) - many, many)]
    keep = (lo[i, 1] <= hi[j, 1]) & (lo[j, 1] <= hi[i, 1])
    return i[keep], j[keep]


def _right_cover(sa: np.ndarray, sb: np.ndarray, parent: np.ndarray, a: np.ndarray,
                 b: np.ndarray, count: np.ndarray) -> np.ndarray | None:
    """(s,) how many shadows cover the right side of each piece sa-sb (s, 2) of edge parent
    (s,) of the outline a-b (e, 2) with counts (e,): the crossings of a ray in +x from a
    point just right of its midpoint (the ray meets an edge that runs up where the point is
    left of it, +count, one that runs down where it is right of it, -count; the piece's own
    edge where it runs down); None where a crossing is in doubt or a piece is level."""
    mid = (sa + sb) / 2
    ay, by = a[None, :, 1], b[None, :, 1]
    y = mid[:, None, 1]
    up = (ay <= y) & (by > y)
    down = (by <= y) & (ay > y)
    r, f = np.nonzero((up | down) & (parent[:, None] != np.arange(len(a))[None]))
    side, sure = _cross(b[f] - a[f], mid[r] - a[f])
    if not sure.all():
        return None
    rise = sb[:, 1] - sa[:, 1]
    if not (np.abs(rise) > DOUBT * np.abs(sb - sa).sum(axis=1)).all():
        return None
    runs_up = up[r, f]
    weight = np.where(runs_up & (side > 0), 1, 0) - np.where(~runs_up & (side < 0), 1, 0)
    wind = np.bincount(r, weight * count[f], len(sa))
    return wind - np.where(rise < 0, count[parent], 0)


def measures(light, cut: np.ndarray, count: np.ndarray, chains, p: np.ndarray,
             normal: np.ndarray, direct: bool = False) -> tuple[np.ndarray, ...]:
    """(n,) measures of the convex polygons cut (n, k, 2), count (n,) (counter-clockwise) less
    the unions bounded by chains (n,) (`boundary`), from p (n, 3) with normals (n, 3)."""
    whole = ring_measures(light, *closed_rings(cut, count), p, normal, direct)
    sizes = np.array([len(c) for c in chains])
    owner = np.repeat(np.arange(len(chains)), sizes)
    if len(owner) == 0:
        return whole
    edges = np.concatenate([c for c in chains if len(c)])
    fan = np.concatenate([np.zeros((len(edges), 1, 2)), edges], axis=1)      # (m, 3, 2)
    signed, _ = _cross(edges[:, 0], edges[:, 1])
    fan[signed < 0] = fan[signed < 0][:, ::-1]
    piece, piece_count = inside(cut[owner], count[owner], fan, np.where(signed != 0, 3, 0))
    got = ring_measures(light, *closed_rings(piece, piece_count), p[owner], normal[owner],
                        direct)
    sign = np.sign(signed)
    return tuple(w - np.bincount(owner, sign * g, len(chains)) for w, g in zip(whole, got))




def split(light, corners: np.ndarray, p: np.ndarray, pix: np.ndarray, tri: np.ndarray,
          heavy: np.ndarray, welded: np.ndarray, only: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray]:
    """The pairs `heavy` (indices into pix, tri) of the pixels `only` (bool, per pixel) whose
    union has a `boundary`: (chains (n,) object, the boundary or None per pixel; the pairs of
    heavy left to `raytrace.arrange`)."""
    chains = np.full(len(p), None, object)
    mine = heavy[only[pix[heavy]]]
    mine = mine[np.argsort(pix[mine], kind="stable")]
    if len(mine) == 0:
        return chains, heavy
    loose, free = pyramid.uncut(light, corners, p, pix[mine], tri[mine])
    starts = np.flatnonzero(np.r_[True, pix[mine][1:] != pix[mine][:-1]])
    for s, e in zip(starts, np.r_[starts[1:], len(mine)]):
        chains[pix[mine[s]]] = boundary(loose[s:e], free[s:e], welded[tri[mine[s:e]]])
    done = found(chains)
    return chains, heavy[~done[pix[heavy]]]


def found(chains: np.ndarray) -> np.ndarray:
    """(n,) bool: where chains (n,) object (`split`) holds a boundary."""
    return np.fromiter((c is not None for c in chains), bool, len(chains))
