"""The covers right of an outline's runs (`raytrace.coverkernels`), on outlines cut to a box
as the block path cuts them: `covers_tied` (a ray only for a run no crossing ties to another)
is certain wherever `covers` (a ray for every run) is and gives the same covers, and each
cover is the outline's winding number just right of its run's first piece, summed here from
the edges' angles in float64 (no ray, no crossing: the witness); on folded sheets, loose
triangles, corners on a grid, counts of two and stars (three edges through one point, where
no crossing may tie two runs)."""

from __future__ import annotations

import numpy as np
import pytest
from shadowcases import loose, on_grid, sheet

from raytrace import windings

pytest.importorskip("numba")


def _stages(tris: np.ndarray, ids: np.ndarray, box: np.ndarray):
    """The winding kernel's stages of one pixel's shadows cut to box, up to its runs: (the
    outline a, b (m, 2), counts (m,), where the box's sides start, both kernels' (certain,
    covers), each run's first edge (m,) and first piece's ends (s, 2) each), or None where
    the cut or the noding is in doubt."""
    from raytrace import clipkernels, coverkernels, outlinekernels, windingkernels as wk
    q = len(tris)
    none = (np.zeros((0, 2, 2)), np.zeros((0, 2), np.int64), np.zeros(0, np.int64))
    big = int(ids.max()) + 1
    meets, sure, wind = clipkernels.survey(tris, 0, q, none, 0, 0, box, windings.DOUBT)
    if not (sure and meets):
        return None
    got = outlinekernels._outline(tris, ids, 0, q, big, none, 0, 0, box)
    ok, ax, ay, bx, by, ia, ib, cnt, sides = clipkernels.clipped(*got, box, big, windings.DOUBT,
                                                                  wind)
    m = len(ax)
    if not ok or m == 0:
        return None
    ok, va, vb = wk._corners(ax, ay, bx, by, ia, ib)
    ok2, ent, pos = wk._crossings(ax, ay, bx, by, ia, ib, cnt, windings.DOUBT, sides)
    if not (ok and ok2):
        return None
    pa, pb, parent, jump, first, before = wk._pieces(ent, pos, m)
    total = np.array([jump[first[e + 1] - 1] for e in range(m)], np.int64)
    root, offset = wk._runs(va, vb, cnt, total)
    rays = coverkernels.covers(pa, pb, first, root, ax, ay, bx, by, cnt, windings.DOUBT, sides)
    tied = coverkernels.covers_tied(ent, pos, before, jump, root, offset, pa, pb, first, ax,
                                    ay, bx, by, cnt, windings.DOUBT, sides)
    return (np.c_[ax, ay], np.c_[bx, by], cnt, sides, rays, tied, root,
            pa[first[:m]], pb[first[:m]], (ent, pos, before, jump, pa, pb, first))


def _winding(a: np.ndarray, b: np.ndarray, cnt: np.ndarray, x: np.ndarray) -> float:
    """The winding number about x (2,) of the edges a -> b (m, 2) with counts: the sum of the
    angles they subtend over 2 pi."""
    u, w = a - x, b - x
    angle = np.arctan2(u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0], (u * w).sum(axis=1))
    return float((cnt * angle).sum() / (2 * np.pi))


def _apart(a: np.ndarray, b: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The distance of x (2,) from each segment a-b (m, 2)."""
    d = b - a
    t = np.clip(((x - a) * d).sum(axis=1) / np.maximum((d * d).sum(axis=1), 1e-300), 0, 1)
    return np.linalg.norm(a + t[:, None] * d - x, axis=1)


def _shapes(rng, kind: int):
    if kind == 0:
        return sheet(rng, int(rng.integers(3, 7)), float(rng.uniform(0.2, 0.8)))
    if kind == 1:
        return loose(rng)
    if kind == 2:
        return on_grid(rng)
    if kind == 3:                                  # counts of two and cancelled copies
        tris, ids = sheet(rng, int(rng.integers(3, 6)), float(rng.uniform(0.2, 0.6)))
        twice, over = rng.random(len(tris)) < 0.3, rng.random(len(tris)) < 0.3
        return np.r_[tris, tris[twice], tris[over][:, ::-1]], \
            np.r_[ids, ids[twice], ids[over][:, ::-1]]
    # a star: long thin triangles through one point, with a sheet about it
    tris, ids = [], []
    for k, (dx, dy) in enumerate([(1, 2), (2, 1), (1, -1), (2, -3), (3, 1)]):
        d, side = np.array([dx, dy], float), np.array([-dy, dx], float) / 16
        tris.append([1.5 - d, 1.5 + d, 1.5 + d + side])
        ids.append(500 + 3 * k + np.arange(3))
    more, more_ids = sheet(rng, 4, 0.3)
    return np.r_[np.array(tris), more], np.r_[np.array(ids), more_ids]


@pytest.mark.parametrize("seed", range(40))
def test_covers_tied_are_the_rays_covers_and_the_windings(seed):
    rng = np.random.default_rng(seed)
    checked = tied_only = 0
    for trial in range(30):
        tris, ids = _shapes(rng, (seed + trial) % 5)
        tris = np.ascontiguousarray(tris, np.float64)
        ids = np.ascontiguousarray(ids, np.int64)
        lo, hi = tris.reshape(-1, 2).min(axis=0), tris.reshape(-1, 2).max(axis=0)
        # a box over part of the shadows, so that the outline crosses its sides
        box = np.r_[lo + rng.uniform(0.1, 0.4, 2) * (hi - lo),
                    hi - rng.uniform(0.1, 0.4, 2) * (hi - lo)]
        got = _stages(tris, ids, box)
        if got is None:
            continue
        a, b, cnt, sides, (ok_r, rays), (ok_t, tied), root, sa, sb, _ = got
        if ok_r:
            assert ok_t and np.array_equal(rays, tied)
        elif ok_t:
            tied_only += 1
        if not ok_t:
            continue
        size = np.abs(np.r_[a, b]).max() + 1.0
        for e in np.flatnonzero((root == np.arange(len(root))) & (np.arange(len(root)) < sides)):
            d = sb[e] - sa[e]
            x = (sa[e] + sb[e]) / 2 + 1e-7 * size * np.array([d[1], -d[0]]) / np.linalg.norm(d)
            near = _apart(a, b, x)
            if np.sort(near)[1 if len(near) > 1 else 0] < 1e-5 * size:
                continue                    # another edge too near the point: no witness
            assert round(_winding(a, b, cnt, x)) == tied[e]
            checked += 1
    assert checked > 30


def test_crossings_that_disagree_leave_the_pixel_in_doubt():
    """Two crossings that tie the same two groups of runs by different differences (a turn
    read the wrong way round at one): `covers_tied` is in doubt, not certain of either."""
    from raytrace import coverkernels
    rng = np.random.default_rng(3)
    found = 0
    for _ in range(200):
        tris, ids = sheet(rng, 5, 0.6)
        tris, ids = np.ascontiguousarray(tris, np.float64), np.ascontiguousarray(ids, np.int64)
        lo, hi = tris.reshape(-1, 2).min(axis=0), tris.reshape(-1, 2).max(axis=0)
        got = _stages(tris, ids, np.r_[lo - 1.0, hi + 1.0])    # the whole outline, no side
        if got is None:
            continue
        a, b, cnt = got[:3]
        ent, pos, before, jump, pa, pb, first = got[9]
        m = len(a)
        # every edge a run of its own: only the crossings tie them
        args = (before, jump, np.arange(m), np.zeros(m, np.int64), pa, pb, first,
                a[:, 0].copy(), a[:, 1].copy(), b[:, 0].copy(), b[:, 1].copy(), cnt,
                windings.DOUBT, m)
        if not coverkernels.covers_tied(ent, pos, *args)[0]:
            continue
        # a crossing whose two edges earlier crossings tie already (a cycle): its turn read
        # the wrong way round
        up = list(range(m))

        def top(r):
            while up[r] != r:
                r = up[r]
            return r
        for g in range(2 * m, len(ent), 2):
            if before[g] < 0 or before[g + 1] < 0:
                continue
            i, j = top(ent[g, 0]), top(ent[g + 1, 0])
            if i != j:
                up[j] = i
                continue
            bad = pos.copy()
            bad[g, 3], bad[g + 1, 3] = -bad[g, 3], -bad[g + 1, 3]
            assert not coverkernels.covers_tied(ent, bad, *args)[0]
            found += 1
            break
    assert found >= 3


@pytest.mark.parametrize("seed", range(12))
def test_the_box_sides_meet_no_edge_but_at_a_shared_corner(seed):
    """`windingkernels._crossings` sweeps an outline cut to a box without the box's sides
    (`clipkernels.clipped`'s stretches): sweeping them too (a box's side tested against
    every edge whose box meets its own) finds no other point, so the pieces are the same
    bytes, and is certain wherever the sweep without them is; on the shapes above, boxes
    over part of them (the outline crossing the sides) and boxes about a corner of a
    triangle (the sides near a corner)."""
    from raytrace import clipkernels, outlinekernels, windingkernels as wk
    rng = np.random.default_rng(seed)
    none = (np.zeros((0, 2, 2)), np.zeros((0, 2), np.int64), np.zeros(0, np.int64))
    compared = 0
    for trial in range(60):
        tris, ids = _shapes(rng, (seed + trial) % 5)
        tris = np.ascontiguousarray(tris, np.float64)
        ids = np.ascontiguousarray(ids, np.int64)
        lo, hi = tris.reshape(-1, 2).min(axis=0), tris.reshape(-1, 2).max(axis=0)
        if trial % 2:
            box = np.r_[lo + rng.uniform(0.1, 0.4, 2) * (hi - lo),
                        hi - rng.uniform(0.1, 0.4, 2) * (hi - lo)]
        else:
            at = tris[rng.integers(len(tris)), rng.integers(3)]
            reach = rng.uniform(1e-3, 0.2) * (hi - lo).max()
            box = np.r_[at - reach * rng.uniform(0.5, 1, 2), at + reach * rng.uniform(0.5, 1, 2)]
        big, q = int(ids.max()) + 1, len(tris)
        meets, sure, wind = clipkernels.survey(tris, 0, q, none, 0, 0, box, windings.DOUBT)
        if not (sure and meets):
            continue
        got = outlinekernels._outline(tris, ids, 0, q, big, none, 0, 0, box)
        ok, ax, ay, bx, by, ia, ib, cnt, sides = clipkernels.clipped(
            *got, box, big, windings.DOUBT, wind)
        m = len(ax)
        if not ok or sides == m:
            continue
        whole = wk._crossings(ax, ay, bx, by, ia, ib, cnt, windings.DOUBT, m)
        cut = wk._crossings(ax, ay, bx, by, ia, ib, cnt, windings.DOUBT, sides)
        assert cut[0] or not whole[0]
        if not whole[0]:
            continue
        # the same points (the sides' ends only: rows 0 .. 2m), so the same pieces
        assert len(whole[1]) == len(cut[1])
        for x, y in zip(wk._pieces(whole[1], whole[2], m), wk._pieces(cut[1], cut[2], m)):
            assert x.tobytes() == y.tobytes()
        compared += len(whole[1]) > 2 * m
    assert compared > 15
