"""`raytrace.windings.boundaries`: the outlines of many pixels' shadows in one pass.  Each
pixel's boundary is the same bytes as its own pass (`boundary`: one pixel) and bounds the
area of GEOS's union of its triangles (shapely, float64); a pixel in doubt (None) among pixels
that are not leaves them alone; pixels share welded corner ids (the same mesh corners seen from
nearby points) and overlap on the light's plane, so a batch that mixed its pixels' edges
would cancel, cross or count them across pixels.  The runs' pointer jumping (`_runs`) is held
to a walk along the runs, edge by edge."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shadowcases import free_but_one, loose, no_area, on_grid, sheet
from strategies import PROFILE, profile

from raytrace import windings
from raytrace.windings import _along, _runs, boundaries, boundary

shapely = pytest.importorskip("shapely")


def _pixel(rng, kind: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One pixel's shadows (triangles, free, ids) of a kind: 0 a folded sheet, 1 loose
    triangles, 2 triangles with corners on a coarse grid from a few ids (touching, collinear:
    often in doubt), 3 a sheet with one shadow not free (None), 4 a T (in doubt), 5 no area."""
    if kind in (0, 3):
        tris, ids = sheet(rng, int(rng.integers(3, 7)), float(rng.uniform(0.2, 0.8)))
    elif kind == 1:
        tris, ids = loose(rng)
    elif kind == 2:
        tris, ids = on_grid(rng)
    elif kind == 4:
        tris = np.array([[[0, 0], [2, 0], [1, 1]], [[1, 0], [1.5, -1], [0.5, -1]]], float)
        ids = np.arange(6).reshape(2, 3)
    else:
        tris, ids = no_area()
    return tris, free_but_one(rng, len(tris), kind == 3), ids


def _union_area(tris: np.ndarray) -> float:
    return float(shapely.union_all(shapely.polygons(tris)).area)


def _fan_area(edges: np.ndarray) -> float:
    a, b = edges[:, 0], edges[:, 1]
    return float((a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum() / 2)


def _check(pixels: list) -> np.ndarray:
    """The batch of pixels against each alone and against GEOS: the batch's boundaries."""
    owner = np.repeat(np.arange(len(pixels)), [len(t) for t, _, _ in pixels])
    got = boundaries(np.concatenate([t for t, _, _ in pixels]),
                     np.concatenate([f for _, f, _ in pixels]),
                     np.concatenate([i for _, _, i in pixels]), owner, len(pixels))
    assert got.shape == (len(pixels),)
    for chain, (tris, free, ids) in zip(got, pixels):
        alone = boundary(tris, free, ids)
        assert (chain is None) == (alone is None)
        if alone is not None:
            assert chain.shape == alone.shape and chain.tobytes() == alone.tobytes()
            want = _union_area(tris)
            assert abs(_fan_area(chain) - want) <= 1e-12 * max(want, 1)
    return got


def test_a_pixel_in_doubt_leaves_its_neighbours_alone():
    """Sheets of the same corner ids, overlapping, around a T (in doubt) and a pixel with a
    shadow not free: those two None, the others their own boundaries and GEOS's areas."""
    rng = np.random.default_rng(5)
    sheet = [_pixel(rng, 0) for _ in range(3)]
    pixels = [sheet[0], _pixel(rng, 4), sheet[1], _pixel(rng, 3), sheet[2], _pixel(rng, 5)]
    got = _check(pixels)
    assert [c is None for c in got] == [False, True, False, True, False, False]
    assert len(got[5]) == 0 and all(len(got[k]) > 10 for k in (0, 2, 4))
    # every pixel settled alone, or none at all
    only = _check([_pixel(rng, 4), _pixel(rng, 5)])
    assert only[0] is None and only[1].shape == (0, 2, 2)


def test_the_same_pixel_twice_in_a_batch():
    """One sheet twice over (the same ids, the same spots), then under other ids: each copy
    is the sheet's own boundary, not the cancelled or doubled outline of both, nor in doubt
    for two ids at one spot."""
    tris, ids = sheet(np.random.default_rng(11), 6, 0.7)
    pixel = (tris, np.ones(len(tris), bool), ids)
    got = _check([pixel, pixel, (tris, pixel[1], ids + 1000)])
    assert len(got[0]) > 10
    assert got[0].tobytes() == got[1].tobytes() == got[2].tobytes()


@settings(profile(), max_examples=40 if PROFILE == "ci" else 1000)
@given(seed=st.integers(0, 2 ** 32 - 1), kinds=st.lists(st.integers(0, 5), min_size=1,
                                                         max_size=6),
       outline=st.sampled_from([1, 9, 40, windings.OUTLINE]))
def test_a_batch_is_its_pixels_one_by_one(seed, kinds, outline):
    """Random batches, noded in parts of `outline` edges (whole pixels) or all at once."""
    rng = np.random.default_rng(seed)
    plain, windings.OUTLINE = windings.OUTLINE, outline
    try:
        _check([_pixel(rng, k) for k in kinds])
    finally:
        windings.OUTLINE = plain


def _walked(ia, ib, count, total):
    """The runs by walking them: from each edge with none before it, then the closed ones
    from their least edge; (first edge of each edge's run, its offset)."""
    out = {}
    for a in set(ia.tolist()) | set(ib.tolist()):
        out[a] = [e for e in range(len(ia)) if ia[e] == a]
    into = {a: [e for e in range(len(ia)) if ib[e] == a] for a in out}
    nxt = [out[ib[e]][0] if len(into[ib[e]]) == 1 and len(out[ib[e]]) == 1
           and count[out[ib[e]][0]] == count[e] else -1 for e in range(len(ia))]
    starts = [e for e in range(len(ia)) if e not in nxt] + list(range(len(ia)))
    root, offset = np.full(len(ia), -1), np.zeros(len(ia))
    for s in starts:
        e, acc = s, 0.0
        while e >= 0 and root[e] < 0:
            root[e], offset[e] = s, acc
            acc += total[e]
            e = nxt[e]
    return root, offset


@settings(profile(), max_examples=60 if PROFILE == "ci" else 1000)
@given(seed=st.integers(0, 2 ** 32 - 1), pixels=st.integers(1, 4))
def test_runs_by_pointer_jumping_are_the_walked_runs(seed, pixels):
    """Random graphs of edges between corners (paths, closed loops, corners of many edges,
    counts that break a run), several pixels (corner ids leading with the pixel)."""
    rng = np.random.default_rng(seed)
    ia, ib, group = [], [], []
    for g in range(pixels):
        # the corners in paths and closed loops (one may hold them all), then a few random
        # edges (corners of many edges)
        corner = rng.permutation(int(rng.integers(2, 80)))
        cut = np.unique(np.r_[0, rng.integers(0, len(corner), int(rng.integers(0, 4))),
                              len(corner)])
        a, b = [], []
        for lo, hi in zip(cut[:-1], cut[1:]):
            run = corner[lo:hi]
            if hi - lo > 2 and rng.random() < 0.5:
                run = np.r_[run, run[0]]
            a.append(run[:-1])
            b.append(run[1:])
        extra = rng.integers(0, len(corner), (int(rng.integers(0, 4)), 2))
        a, b = np.concatenate(a + [extra[:, 0]]), np.concatenate(b + [extra[:, 1]])
        keep = rng.permutation(np.flatnonzero(a != b))       # runs in no order of edges
        ia.append(g * 1000 + a[keep])
        ib.append(g * 1000 + b[keep])
        group.append(np.full(len(keep), g))
    ia, ib, group = np.concatenate(ia), np.concatenate(ib), np.concatenate(group)
    count = np.where(rng.random(len(ia)) < 0.05, 2.0, 1.0)      # a few break their runs
    total = rng.integers(-2, 3, len(ia)).astype(float)
    root, offset = _runs(np.unique(np.r_[ia, ib], return_inverse=True)[1], count, total, group)
    want_root, want_offset = _walked(ia, ib, count, total)
    assert (root == want_root).all() and (offset == want_offset).all()


def test_corner_ids_too_big_for_one_key():
    """Corner ids near 2 ** 40 (a pixel's edges then sorted by two keys, not one): the same
    boundaries as the same pixels with small ids."""
    rng = np.random.default_rng(3)
    pixels = [_pixel(rng, k) for k in (0, 4, 1, 0, 2)]
    got = _check(pixels)
    far = _check([(t, f, i + 2 ** 40) for t, f, i in pixels])
    for small, big in zip(got, far):
        assert (small is None and big is None) or small.tobytes() == big.tobytes()
    assert sum(c is not None for c in got) >= 3


@pytest.mark.parametrize("ties", [False, True])
def test_points_along_their_edges_in_lexsorts_order(ties):
    """`_along` (a quick sort and a radix sort) is np.lexsort's order, ties (three edges
    through one point) included; the pieces' floats follow it."""
    rng = np.random.default_rng(7)
    for edges in (5, 300, 70000):                    # 70000 edges: not a radix sort's 16 bits
        edge = rng.integers(0, edges, 4 * edges)
        t = rng.integers(0, 8, len(edge)) / 8 if ties else rng.random(len(edge))
        assert (_along(edge, t) == np.lexsort((t, edge))).all()
