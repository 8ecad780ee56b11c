"""`windings.boundaries` in numba (`raytrace.windingkernels`) against its numpy path, byte for
byte: every pixel's chain the same edges, floats and order, and the same doubt (None), on
random batches (folded sheets of shared corner ids, loose crossing triangles, corners on a
coarse grid: touching, collinear, in doubt; a shadow not free, no area, a pixel with no
shadows, the same triangle twice: counts of 2, edges crossed at one point by two others: ties
along an edge, one corner id at two spots: which shadow's edge the outline keeps; a T, two
edges leaving a shared corner along one line, a level edge, two corners of different ids at
one point: in doubt) and on the batches of
a noisy ball's exact soft shadow.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shadowcases import free_but_one, loose, no_area, noisy_ball, on_grid, sheet
from strategies import PROFILE, profile

from raytrace import polygons, windings

pytest.importorskip("numba")


def _star(rng) -> tuple[np.ndarray, np.ndarray]:
    """Thin triangles whose long edges all pass through one point (0.5, 0.5) at a dyadic
    angle: an edge crossed by two others at one point (the same t twice along it)."""
    tris, ids = [], []
    for k, (dx, dy) in enumerate([(1, 2), (2, 1), (1, -1), (2, -3), (3, 1)][:rng.integers(2, 6)]):
        d = np.array([dx, dy], float) / 4
        side = np.array([-dy, dx], float) / 64
        a, b = 0.5 - d, 0.5 + d
        tris.append([a, b, b + side] if rng.random() < 0.5 else [b, a, a - side])
        ids.append(10 * k + np.arange(3))
    return np.array(tris), np.array(ids)


def _pixel(rng, kind: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One pixel's shadows (triangles, free, ids) of a kind: 0 a folded sheet, 1 loose
    triangles, 2 corners on a coarse grid from a few ids, 3 a sheet with a shadow not free,
    4 no area, 5 a sheet with some triangles twice (counts of 2) and some turned over (they
    cancel), 6 a star (ties along an edge), 7 a sheet whose shadows each see their corners a
    little apart (one id at several spots), 8 no shadows at all, 9 a T, 10 two edges from a
    shared corner along one line, 11 a level edge, 12 two corners of different ids at one
    point (the four in doubt)."""
    if kind in (0, 3, 5, 7):
        tris, ids = sheet(rng, int(rng.integers(3, 7)), float(rng.uniform(0.2, 0.8)))
        if kind == 5:
            twice = rng.random(len(tris)) < 0.3
            over = rng.random(len(tris)) < 0.3
            tris = np.r_[tris, tris[twice], tris[over][:, ::-1]]
            ids = np.r_[ids, ids[twice], ids[over][:, ::-1]]
        if kind == 7:
            tris = tris + rng.normal(0, 1e-9, tris.shape) * (rng.random(tris.shape) < 0.3)
    elif kind == 1:
        tris, ids = loose(rng)
    elif kind == 2:
        tris, ids = on_grid(rng)
    elif kind == 6:
        tris, ids = _star(rng)
    elif kind == 8:
        tris, ids = np.zeros((0, 3, 2)), np.zeros((0, 3), np.int64)
    elif kind == 12:
        # two corners of different ids at one point (a triangle touching another's corner
        # with its own, not welded): in doubt, mapped as the T is
        tris = np.array([[[0, 0], [2, 0], [1, 1]], [[2, 0], [4, 0], [3, -1]]], float)
        ids = np.array([[0, 1, 2], [3, 4, 5]])
        turn = rng.integers(1, 4, (2, 2)) * [[1, -1], [1, 1]]              # det > 0
        tris = tris @ turn * 2.0 ** rng.integers(-3, 4) + rng.integers(-8, 8, 2)
    elif kind in (9, 10):
        # a T (a corner inside another's edge) or two edges from a shared corner along one
        # line, mapped by a random integer matrix (exact: no edge level), moved and scaled by
        # a power of two, among a few loose triangles
        tris = np.array([[[0, 0], [4, 0], [2, 2]],
                         [[2, 0], [3, -2], [1, -2]] if kind == 9 else
                         [[0, 0], [2, 0], [1, -2]]], float)
        ids = np.array([[0, 1, 2], [3, 4, 5] if kind == 9 else [0, 4, 5]])
        turn = rng.integers(1, 4, (2, 2)) * [[1, -1], [1, 1]]              # det > 0
        tris = tris @ turn * 2.0 ** rng.integers(-3, 4) + rng.integers(-8, 8, 2)
        q = int(rng.integers(0, 4))
        tris = np.r_[tris, rng.uniform(20, 30, (q, 3, 2))]
        ids = np.r_[ids, np.arange(3 * q).reshape(q, 3) + 100]
    elif kind == 11:
        # a triangle whose edge from its least corner id (its run's first) runs level
        tris = np.array([[[0, 0], [1, 0], [0, 1]]], float) * rng.integers(1, 9) + \
            rng.integers(-8, 8, 2)
        ids = np.array([[0, 1, 2]])
    else:
        tris, ids = no_area()
    return tris, free_but_one(rng, len(tris), kind == 3), ids


def _same(uncut, free, ids, owner, n, monkeypatch) -> np.ndarray:
    """boundaries in numba and in numpy (its kernels' module switched off): the same None
    and the same bytes per pixel; the kernel's chains."""
    fast = windings.boundaries(uncut, free, ids, owner, n)
    with monkeypatch.context() as m:
        m.setitem(sys.modules, "raytrace.windingkernels", None)      # import fails: numpy
        assert polygons.kernels("windingkernels") is None
        slow = windings.boundaries(uncut, free, ids, owner, n)
    assert polygons.kernels("windingkernels") is not None
    assert fast.shape == slow.shape == (n,)
    for a, b in zip(fast, slow):
        assert (a is None) == (b is None)
        if b is not None:
            assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
    return fast


def _batch(pixels, monkeypatch) -> np.ndarray:
    owner = np.repeat(np.arange(len(pixels)), [len(t) for t, _, _ in pixels])
    return _same(np.concatenate([t for t, _, _ in pixels]),
                 np.concatenate([f for _, f, _ in pixels]),
                 np.concatenate([i for _, _, i in pixels]), owner, len(pixels), monkeypatch)


@pytest.mark.parametrize("kind", range(13))
def test_each_kind_of_pixel_is_numpys_bytes(kind, monkeypatch):
    """Twelve pixels of one kind in a batch; the kinds meant to settle do, mostly."""
    rng = np.random.default_rng(kind)
    got = _batch([_pixel(rng, kind) for _ in range(12)], monkeypatch)
    settled = sum(c is not None for c in got)
    if kind in (0, 1, 5, 6, 7):
        assert settled >= 6 and max(len(c) for c in got if c is not None) >= 6
    if kind in (3, 9, 10, 11, 12):
        assert settled == 0
    if kind in (4, 8):
        assert all(c is not None and c.shape == (0, 2, 2) for c in got)


def test_ties_along_an_edge_and_counts_of_two(monkeypatch):
    """A star (two crossings at one t along an edge: a piece of no length between them, its
    place in the chain set by the order of the ties) and doubled triangles (count 2)."""
    rng = np.random.default_rng(1)
    stars = [_pixel(rng, 6) for _ in range(20)]
    got = _batch(stars, monkeypatch)
    flat = [c for c in got if c is not None]
    assert any(((c[:, 0] == c[:, 1]).all(axis=1)).any() for c in flat)      # a tie's piece
    doubled = _batch([_pixel(rng, 5) for _ in range(12)], monkeypatch)
    assert sum(c is not None for c in doubled) >= 6


@settings(profile(), max_examples=40 if PROFILE == "ci" else 1000)
@given(seed=st.integers(0, 2 ** 32 - 1), kinds=st.lists(st.integers(0, 12), min_size=1,
                                                         max_size=8),
       shift=st.sampled_from([0, 1000, 2 ** 40]),
       outline=st.sampled_from([1, 9, 40, windings.OUTLINE]))
def test_random_batches_are_numpys_bytes(seed, kinds, shift, outline, monkeypatch):
    """Random batches of every kind, the ids shifted (near 2 ** 40: a key of two ids no longer
    fits one int64 with the pixel's), numpy's path noded in parts of `outline` edges (whole
    pixels) or all at once."""
    monkeypatch.setattr(windings, "OUTLINE", outline)
    rng = np.random.default_rng(seed)
    _batch([(t, f, i + shift) for t, f, i in (_pixel(rng, k) for k in kinds)], monkeypatch)


def test_a_noisy_balls_batches_are_numpys_bytes(monkeypatch):
    """The batches `windings.split` hands `boundaries` in the exact soft shadow of a noisy
    ball on a floor under a rect light (pixel by pixel: no block shares its outline,
    `raytrace.blockwindings`): each the same bytes both ways."""
    pytest.importorskip("trimesh")
    import raytrace.exact_soft
    from raytrace.exact_soft import exact_visibility
    from shadowvol.scene import AreaLight
    scene = noisy_ball(AreaLight("rect", [0.0, 2.5, 0.0], normal=[0, -1, 0], size=[1.2, 1.2],
                                 samples=4))
    seen, plain = [], windings.boundaries

    def keep(*args):
        seen.append(args)
        return plain(*args)
    with monkeypatch.context() as m:
        m.setattr(windings, "boundaries", keep)
        m.setattr(raytrace.exact_soft, "BLOCK", 0)
        exact_visibility(scene)
    assert seen
    settled = 0
    for args in seen:
        settled += sum(c is not None for c in _same(*args, monkeypatch))
    assert settled >= 10


@pytest.mark.parametrize("seed", range(6))
def test_corners_number_ids_one_to_one_and_find_two_at_one_point(seed):
    """`windingkernels._corners` against a brute force: one number an id and one id a
    number, and certain exactly where no two ids (each at its first place among the starts,
    then the ends) lie at one point, -0.0 and 0.0 as one."""
    from raytrace import windingkernels
    rng = np.random.default_rng(seed)
    m = int(rng.integers(1, 60))
    ia, ib = rng.integers(0, 2 * m, m), rng.integers(0, 2 * m, m)
    # a point an id on a grid (seeds 3-5: no two ids at one point), some ids at their later
    # places elsewhere
    grid = np.stack(np.meshgrid(np.arange(-7, 8), np.arange(-7, 8)), -1).reshape(-1, 2) * 0.5
    pick = rng.permutation(len(grid)) if seed >= 3 else rng.integers(0, len(grid), len(grid))
    spot = {}
    for i in np.r_[ia, ib]:
        spot.setdefault(int(i), grid[pick[len(spot)]])
    a = np.array([spot[int(i)] for i in ia])
    b = np.array([spot[int(i)] if rng.random() < 0.9 else spot[int(i)] + 1e-3 for i in ib])
    a[a == 0] *= -1.0 if seed % 2 else 1.0    # -0.0 at half the seeds
    ok, va, vb = windingkernels._corners(a[:, 0].copy(), a[:, 1].copy(), b[:, 0].copy(),
                                         b[:, 1].copy(), ia, ib)
    ids, numbers = np.r_[ia, ib], np.r_[va, vb]
    assert len(set(zip(ids.tolist(), numbers.tolist()))) == len(set(ids.tolist())) == \
        len(set(numbers.tolist()))
    first = {}
    for i, xy in zip(ids.tolist(), np.r_[a, b].tolist()):
        first.setdefault(i, (xy[0] + 0.0, xy[1] + 0.0))
    assert bool(ok) == (len(set(first.values())) == len(first)) == (seed >= 3)
    # -0.0 and 0.0 are one point: two ids there are in doubt
    signed = np.array([-0.0, 0.0]), np.array([1.0, 1.0]), np.array([2.0, 3.0])
    assert not windingkernels._corners(*signed, np.array([4.0, 5.0]), np.array([0, 1]),
                                       np.array([2, 3]))[0]


def _pair_by_turns(ai, bi, ia_i, ib_i, aj, bj, ia_j, ib_j, margin):
    """`windingkernels._pair`'s state (1 cross, 0 apart or a shared corner only, -1 in doubt)
    as it was before shared corners were taken first: the four turns, then the corner's
    test where the ids share one (Python floats: the same IEEE products)."""
    def turn(ux, uy, vx, vy, size):
        c = ux * vy - uy * vx
        return c, abs(c) > margin * (size * (abs(vx) + abs(vy)))
    (axi, ayi), (bxi, byi), (axj, ayj), (bxj, byj) = ai, bi, aj, bj
    dxi, dyi, dxj, dyj = bxi - axi, byi - ayi, bxj - axj, byj - ayj
    si, sj = abs(dxi) + abs(dyi), abs(dxj) + abs(dyj)
    ci, oi = turn(dxi, dyi, axj - axi, ayj - ayi, si)
    di, pi = turn(dxi, dyi, bxj - axi, byj - ayi, si)
    if oi and pi and ci * di > 0:
        return 0
    cj, oj = turn(dxj, dyj, axi - axj, ayi - ayj, sj)
    dj, pj = turn(dxj, dyj, bxi - axj, byi - ayj, sj)
    shared = ia_i in (ia_j, ib_j) or ib_i in (ia_j, ib_j)
    apart = oj and pj and cj * dj > 0
    cross = oi and pi and oj and pj and ci * di < 0 and cj * dj < 0 and not shared
    if not (apart or cross or shared):
        return -1
    if shared and not apart:
        at_a = ia_i in (ia_j, ib_j)
        x, y = (axi, ayi) if at_a else (bxi, byi)
        ux, uy = ((bxi - x, byi - y) if at_a else (axi - x, ayi - y))
        vx, vy = ((bxj - x, byj - y) if ia_j == (ia_i if at_a else ib_i) else
                  (axj - x, ayj - y))
        if not (turn(ux, uy, vx, vy, abs(ux) + abs(uy))[1] or ux * vx + uy * vy < 0):
            return -1
    return 1 if cross else 0


@pytest.mark.parametrize("seed", range(6))
def test_two_edges_at_one_corner_are_in_doubt_only_where_they_may_overlap(seed):
    """`windingkernels._pair` of two edges sharing a corner id at one point: in doubt (-1)
    exactly where their other ends leave it along one line the same way (a perpendicular
    offset of 1e-13 of their length, well within DOUBT), else apart (0: opposite ways, or
    an angle of 1e-3 and more), never a crossing; either edge first, the corner at either
    end of each, -0.0 for 0.0 in one copy.  With the corner's two copies a rounding or a
    thousandth apart (one id at two points) and on pairs that share nothing, the same
    state as the four turns gave before the corner's shortcut (`_pair_by_turns`)."""
    from raytrace import windingkernels
    rng = np.random.default_rng(seed)
    margin = windings.DOUBT

    def pair(i, j, ids_i, ids_j):
        return int(windingkernels._pair(*i[0], *i[1], *ids_i, *j[0], *j[1], *ids_j,
                                        margin)[0])
    for _ in range(200):
        corner = rng.normal(0, 10.0 ** rng.integers(-2, 3), 2)
        u = rng.normal(0, 1, 2) * 10.0 ** rng.uniform(-2, 1)
        same, near = rng.random() < 0.5, rng.random() < 0.5
        v = u * rng.uniform(0.2, 3) * (1 if same else -1)
        v = v + np.array([-v[1], v[0]]) * (1e-13 if near else rng.uniform(1e-3, 1))
        if rng.random() < 0.2:
            corner[0] = 0.0
        i = [tuple(corner), tuple(corner + u)]
        j = [(-0.0 if corner[0] == 0 else corner[0], corner[1]), tuple(corner + v)]
        ids_i, ids_j = [7, 3], [7, 11]
        if rng.random() < 0.5:
            i, ids_i = i[::-1], ids_i[::-1]
        if rng.random() < 0.5:
            j, ids_j = j[::-1], ids_j[::-1]
        want = -1 if near and same else 0
        assert pair(i, j, ids_i, ids_j) == pair(j, i, ids_j, ids_i) == want, (i, j)
        # the corner's copies a rounding or a little apart: the turns decide, as before
        for off in (None, rng.normal(0, 1e-3 * np.abs(u).sum(), 2)):
            k = [(tuple(np.nextafter(np.array(q), np.inf)) if off is None else
                  tuple(np.array(q) + off)) if n == 7 else q for q, n in zip(j, ids_j)]
            assert pair(i, k, ids_i, ids_j) == _pair_by_turns(*i, *ids_i, *k, *ids_j, margin)
            assert pair(k, i, ids_j, ids_i) == _pair_by_turns(*k, *ids_j, *i, *ids_i, margin)
        # and two edges that share no corner
        w = [tuple(rng.normal(0, 1, 2)), tuple(rng.normal(0, 1, 2))]
        assert pair(i, w, ids_i, [20, 21]) == _pair_by_turns(*i, *ids_i, *w, 20, 21, margin)


@pytest.mark.parametrize("seed", range(6))
def test_the_stable_order_is_numpys(seed):
    """`outlinekernels._stable` (by insertion up to FEW keys, else a quick sort and its runs
    of ties) gives np.argsort(kind="stable")'s order: floats with many ties, -0.0 beside 0.0,
    NaNs (the insertion gives way to the sort), int64 keys; 0 to 3 FEW keys."""
    from raytrace.outlinekernels import FEW, _stable
    rng = np.random.default_rng(seed)
    for n in [0, 1, 2, FEW - 1, FEW, FEW + 1, *rng.integers(0, 3 * FEW, 20)]:
        floats = rng.integers(-4, 5, n) * 0.5
        floats[rng.random(n) < 0.2] = -0.0
        with_nan = floats.copy()
        with_nan[rng.random(n) < 0.1] = np.nan
        ints = rng.integers(-3, 4, n) * (1 << 40)
        for key in (floats, with_nan, ints, rng.random(n)):
            assert np.array_equal(_stable(key), np.argsort(key, kind="stable")), (n, key)
