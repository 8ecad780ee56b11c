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
