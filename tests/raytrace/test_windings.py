"""`raytrace.windings`: the union of triangles measured from its outline's winding numbers,
against GEOS's union of the same triangles (shapely, float64), on random overlapping triangles
and on folded sheets of triangles sharing corners (a projected bumpy surface crosses itself)."""

from __future__ import annotations

import numpy as np
import pytest

from raytrace.windings import boundary

shapely = pytest.importorskip("shapely")


def _fan_area(edges: np.ndarray) -> float:
    """The area bounded by edges (e, 2, 2) (the region on their left): the shoelace sum."""
    a, b = edges[:, 0], edges[:, 1]
    return float((a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum() / 2)


def _union_area(tris: np.ndarray) -> float:
    return float(shapely.union_all(shapely.polygons(tris)).area)


def _sheet(rng, n: int) -> tuple[np.ndarray, np.ndarray]:
    """A grid of n x n corners jittered so that it folds over itself: (triangles (q, 3, 2),
    their corner ids (q, 3))."""
    x, y = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float))
    pts = np.c_[x.ravel(), y.ravel()] + rng.normal(0, 0.7, (n * n, 2))
    k = np.arange(n * n).reshape(n, n)[:-1, :-1].ravel()
    ids = np.r_[np.c_[k, k + 1, k + n + 1], np.c_[k, k + n + 1, k + n]]
    return pts[ids], ids


@pytest.mark.parametrize("seed", range(8))
def test_outline_windings_measure_the_union(seed):
    rng = np.random.default_rng(seed)
    if seed % 2:
        tris = rng.uniform(-1, 1, (40, 3, 2))
        ids = np.arange(120).reshape(40, 3)
    else:
        tris, ids = _sheet(rng, 7)
    got = boundary(tris, np.ones(len(tris), bool), ids)
    assert got is not None
    want = _union_area(tris)
    assert abs(_fan_area(got) - want) <= 1e-12 * max(want, 1)
    # the sum of the triangles' areas is not the union's: overlaps were there
    u, v = tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]
    single = np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]).sum() / 2
    assert single > want * 1.05


def test_doubt_falls_back():
    """A corner of one triangle on another's edge (a T): no measure from the windings."""
    tris = np.array([[[0, 0], [2, 0], [1, 1]], [[1, 0], [1.5, -1], [0.5, -1]]], float)
    assert boundary(tris, np.ones(2, bool), np.arange(6).reshape(2, 3)) is None
    assert boundary(tris, np.array([True, False]), np.arange(6).reshape(2, 3)) is None


def _rect_light():
    """A 4 x 4 rect light at the origin, facing +z (its plane's coordinates are x, y)."""
    from raytrace.lightshapes import FramedLight
    hull = np.array([[-2.0, -2.0], [2.0, -2.0], [2.0, 2.0], [-2.0, 2.0]])
    return FramedLight(np.zeros(3), np.array([0.0, 0.0, 1.0]), np.eye(3)[:2], hull, None,
                       None, 16.0, 2.0 ** -44)


def _pieces(rng, tris: np.ndarray, n: int) -> list:
    """n convex pieces for `measures`' loose shadows: a random quad, a triangle of the sheet
    itself (its edges on the outline's), two sharing an edge (their intersection collapses to
    it), each in either orientation."""
    shared = rng.uniform(-1.5, 1.5, (2, 2))
    out = [np.array(shapely.convex_hull(shapely.multipoints(rng.uniform(-2.5, 2.5, (6, 2))))
                    .exterior.coords)[:-1],
           tris[rng.integers(len(tris))],
           np.r_[shared, rng.uniform(-1.5, 1.5, (1, 2))],
           np.r_[shared[::-1], rng.uniform(-1.5, 1.5, (1, 2))]]
    return [x if rng.random() < 0.5 else x[::-1] for x in out[:n]]


@pytest.mark.parametrize("seed", range(12))
def test_measures_take_the_loose_shadows_away_by_inclusion_and_exclusion(seed):
    """A pixel's windings union A and up to four convex shadows B apart (`split`'s loose ones,
    at a contact): the light's part outside both, by inclusion and exclusion over B's pieces,
    against GEOS's difference of the same polygons (area and Lambert's irradiance, measured
    on GEOS's rings by `regions.measure`)."""
    from raytrace.regions import measure
    from raytrace.windmeasures import measures, turned
    rng = np.random.default_rng(seed)
    light = _rect_light()
    tris, ids = _sheet(rng, 6)
    tris = (tris - 2.5) * 0.6
    chain = boundary(tris, np.ones(len(tris), bool), ids)
    assert chain is not None
    # the light cut to p's side: a convex part of its square
    cut = np.array([[-2.0, -2.0], [2.0, -2.0], [2.0, 1.2 - seed * 0.1], [-2.0, 1.9]])
    p = np.array([[0.3, -0.2, 3.0]])
    normal = np.array([[0.1, 0.2, -1.0]]) / np.linalg.norm([0.1, 0.2, -1.0])
    pieces = _pieces(rng, tris, 1 + seed % 4)
    width = max(len(x) for x in pieces)
    flat = np.zeros((len(pieces), width, 2))
    count = np.array([len(x) for x in pieces])
    for j, x in enumerate(pieces):
        flat[j, :len(x)] = x
    ccw, sure = turned(flat, count)
    assert sure.all()
    loose = np.full(1, None, object)
    loose[0] = (ccw, count)
    got = measures(light, cut[None], np.array([4]), np.array([chain] + [None], object)[:1],
                   p, normal, False, loose)
    seen = shapely.Polygon(cut).difference(shapely.union_all(
        np.r_[shapely.polygons(tris), [shapely.Polygon(x) for x in pieces]]))
    want = measure(shapely, light, np.array([seen], object), p, normal)
    assert abs(got[0][0] - want[0][0]) <= 1e-12 * 16
    assert abs(got[1][0] - want[1][0]) <= 1e-12 * max(abs(want[1][0]), 1)
    # and the pieces mattered: without them the measure is another
    alone = measures(light, cut[None], np.array([4]), np.array([chain] + [None], object)[:1],
                     p, normal)
    assert alone[0][0] - got[0][0] > 1e-6


def test_turned_says_where_the_corners_do_not_certainly_turn_one_way():
    from raytrace.windmeasures import turned
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    flat = np.zeros((4, 5, 2))
    flat[0, :4] = square
    flat[1, :4] = square[[0, 3, 2, 1]]                           # clockwise: turned
    flat[2, :3] = [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]           # collinear
    flat[3, :5] = np.r_[square, square[3:] + [0.0, 1e-18]]       # a corner twice
    out, sure = turned(flat, np.array([4, 4, 3, 5]))
    assert sure.tolist() == [True, True, False, False]
    assert np.array_equal(out[0, :4], square)
    assert np.array_equal(out[1, :4], square[[1, 2, 3, 0]])     # the same corners, reversed
    assert not out[:2, 4:].any()
