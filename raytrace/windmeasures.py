"""The measures of a crowded pixel's view of an area light (`raytrace.exact_soft`) from its
shadows' union A known by its boundary alone (`raytrace.windings`) and, at a contact, a few
convex shadows B besides: the light's part seen from p (convex) less both.

Area and Lambert's irradiance are boundary integrals, so the measure of a convex polygon X
less A is X's own less that of the fan of signed triangles from the light's centre over A's
boundary, each clipped to X (`regions.inside`).  Less B too, by inclusion and exclusion over
B's pieces: m(cut - A - B) = m(cut - A) + the sum over every non-empty set S of them of
(-1)^|S| m(X_S - A), X_S = cut and the pieces of S; a fan is clipped by cut and by each piece of
S in turn (by those polygons' own edges, never by X_S's, which may have collapsed to a segment
or a point where two pieces share an edge), so each piece must be certainly convex (`turned`).
The fans of a rect light, without `direct`, are clipped and measured in numba where it
loads (`raytrace.measurekernels`: the same areas, V, bit for bit).
"""

from __future__ import annotations

import numpy as np

from . import polygons
from .regions import closed_rings, inside, ring_measures
from .windings import _cross

__all__ = ["measures", "turned"]


def measures(light, cut: np.ndarray, count: np.ndarray, chains, p: np.ndarray,
             normal: np.ndarray, direct: bool = False, loose=None) -> tuple[np.ndarray, ...]:
    """(n,) measures of the convex polygons cut (n, k, 2), count (n,) (counter-clockwise) less
    the unions bounded by chains (n,) (`windings.boundary`) and, where loose (n,) object holds
    them (`windings.split`), a few convex shadows besides ((flat (r, k, 2), count (r,)) each,
    counter-clockwise and certainly convex: `turned`; None where none), from p (n, 3) with
    normals (n, 3): the module's inclusion and exclusion."""
    n = len(cut)
    at = [k for k in range(n) if loose is not None and loose[k] is not None]
    if not at:
        return _less(light, cut, count, [(cut, count)], chains, np.arange(n), p, normal, direct)
    owner, sets = [], []
    for k in at:
        for subset in range(1, 1 << len(loose[k][0])):
            owner.append(k)
            sets.append([j for j in range(len(loose[k][0])) if subset >> j & 1])
    owner = np.r_[np.arange(n), owner]
    width = max([cut.shape[1]] + [loose[k][0].shape[1] for k in at])
    clippers = [(_widen(cut, width)[owner], count[owner])]
    for level in range(max(len(x) for x in sets)):
        poly, many = np.zeros((len(owner), width, 2)), np.zeros(len(owner), np.int64)
        for i, (k, chosen) in enumerate(zip(owner[n:].tolist(), sets)):
            if level < len(chosen):
                flat, counts = loose[k]
                poly[n + i, :flat.shape[1]] = flat[chosen[level]]
                many[n + i] = counts[chosen[level]]
        clippers.append((poly, many))
    # X_S: cut clipped by each piece of S (the region measured; empty ones left out)
    region, size = clippers[0]
    for poly, many in clippers[1:]:
        region, size = _clip_rows(poly, many, region, size)
    sign = np.r_[np.ones(n), [(-1.0) ** len(x) for x in sets]]
    use = np.flatnonzero((size >= 3) | (np.arange(len(owner)) < n))
    got = _less(light, region[use], size[use], [(c[use], m[use]) for c, m in clippers], chains,
                owner[use], p[owner[use]], normal[owner[use]], direct)
    return tuple(np.bincount(owner[use], sign[use] * m, n) for m in got)


def _less(light, region: np.ndarray, size: np.ndarray, clippers: list, chains,
          owner: np.ndarray, p: np.ndarray, normal: np.ndarray, direct: bool
          ) -> tuple[np.ndarray, ...]:
    """(r,) measures of the convex polygons region (r, k, 2), size (r,) less the unions bounded
    by chains[owner] (r,): the fan of signed triangles from the light's centre over each
    chain's edges, clipped by each of clippers' convex counter-clockwise polygons ((r, k, 2),
    (r,) each; count 0: none) in turn, whose common part the region is.  In numba, one
    row at a time, where it loads (`raytrace.measurekernels`: the areas' bytes; a disk light
    and `direct` stay in numpy)."""
    loaded = None if direct or light.radius is not None else \
        polygons.kernels("measurekernels")
    mode = None if loaded is None else _matmul_mode(loaded, light.axes)
    if mode is not None:
        return _kernel(loaded, mode, light, region, size, clippers, chains, owner, p, normal)
    whole = ring_measures(light, *closed_rings(region, size), p, normal, direct)
    sizes = np.array([len(chains[k]) for k in owner], np.int64)
    which = np.repeat(np.arange(len(owner)), sizes)
    if len(which) == 0:
        return whole
    edges = np.concatenate([chains[k] for k in owner if len(chains[k])])
    fan = np.concatenate([np.zeros((len(edges), 1, 2)), edges], axis=1)      # (m, 3, 2)
    signed, _ = _cross(edges[:, 0], edges[:, 1])
    fan[signed < 0] = fan[signed < 0][:, ::-1]
    (cut, count), more = clippers[0], clippers[1:]
    piece, piece_count = inside(cut[which], count[which], fan, np.where(signed != 0, 3, 0))
    for poly, many in more:
        piece, piece_count = _clip_rows(poly[which], many[which], piece, piece_count)
    got = ring_measures(light, *closed_rings(piece, piece_count), p[which], normal[which],
                        direct)
    sign = np.sign(signed)
    return tuple(w - np.bincount(which, sign * g, len(owner)) for w, g in zip(whole, got))


def _matmul_mode(loaded, axes: np.ndarray) -> int | None:
    """How numpy's matmul (its BLAS) rounds plane points (n, 2) @ axes (2, 3) here, as
    `measurekernels.products` names it (0, 1 or 2: the same bytes on a probe of 4 and of 512
    random points), or None where it is none of them (then numpy measures)."""
    axes = np.ascontiguousarray(axes, np.float64)
    rng = np.random.default_rng(0)
    probe = rng.normal(size=(516, 2)) * 10.0 ** rng.integers(-3, 3, (516, 1))
    for mode in (1, 0, 2):
        if all(np.array_equal(loaded.products(a, axes, mode), a @ axes)
               for a in (probe[:4].copy(), probe[4:].copy())):
            return mode
    return None


def _kernel(loaded, mode: int, light, region: np.ndarray, size: np.ndarray, clippers: list,
            chains, owner: np.ndarray, p: np.ndarray, normal: np.ndarray
            ) -> tuple[np.ndarray, ...]:
    """`_less` by `measurekernels.less`: the clippers stacked, the chains in one array."""
    width = max(poly.shape[1] for poly, _ in clippers)
    polys = np.stack([_widen(poly, width) for poly, _ in clippers])
    counts = np.stack([many for _, many in clippers]).astype(np.int64)
    sizes = np.array([0 if chain is None else len(chain) for chain in chains], np.int64)
    start = np.r_[0, np.cumsum(sizes)]
    edges = np.concatenate([chains[k] for k in np.flatnonzero(sizes)]) if start[-1] else \
        np.zeros((0, 2, 2))
    return loaded.less(np.ascontiguousarray(region, np.float64), size.astype(np.int64), polys,
                       counts, np.ascontiguousarray(edges, np.float64), start,
                       owner.astype(np.int64), np.ascontiguousarray(p, np.float64),
                       np.ascontiguousarray(normal, np.float64),
                       np.ascontiguousarray(light.center, np.float64),
                       np.ascontiguousarray(light.axes, np.float64), mode)


def _clip_rows(poly: np.ndarray, many: np.ndarray, inner: np.ndarray, count: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """`regions.inside` of the rows where many (r,) > 0 (the others as they are): inner (r, k,
    2), count (r,) clipped by each edge of the convex counter-clockwise polygons poly (r, m,
    2), many (r,)."""
    on = np.flatnonzero(many > 0)
    if len(on) == 0:
        return inner, count
    got, got_count = inside(poly[on], many[on], inner[on], count[on])
    out = _widen(inner, max(inner.shape[1], got.shape[1]))
    out[on] = _widen(got, out.shape[1])
    count = count.copy()
    count[on] = got_count
    return out, count


def turned(flat: np.ndarray, count: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Convex polygons flat (r, k, 2), count (r,) in either orientation: (the same turned
    counter-clockwise (r, k, 2), zero past each count; (r,) bool: every corner certainly turns
    the same way (`_turn`'s doubt), so its edges bound it)."""
    r, k = len(flat), flat.shape[1]
    at = np.arange(k)[None]
    valid = at < count[:, None]
    n = np.maximum(count, 1)[:, None]
    nxt = np.take_along_axis(flat, ((at + 1) % n)[..., None], 1)
    after = np.take_along_axis(flat, ((at + 2) % n)[..., None], 1)
    u, v = nxt - flat, after - nxt
    turn, sure = _cross(u, v)
    left = ((turn > 0) & sure) | ~valid
    right = ((turn < 0) & sure) | ~valid
    ok = (left.all(axis=1) | right.all(axis=1)) & (count >= 3)
    back = ~left.all(axis=1)
    index = np.where(back[:, None] & valid, count[:, None] - 1 - at, at)
    out = np.take_along_axis(flat, index[..., None], 1)
    out[~valid] = 0.0
    return out, ok


def _widen(flat: np.ndarray, width: int) -> np.ndarray:
    """flat (n, k, 2) zero-padded to (n, width, 2) (k <= width)."""
    out = np.zeros((len(flat), width, 2))
    out[:, :flat.shape[1]] = flat
    return out
