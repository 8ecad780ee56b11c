"""Property: the near pieces' cheap query (`raytrace.neargrid`) never leaves out a triangle
that the float64 test meets, so `EmbreeBackend.occluded_leaving` answers as the float64 walk
(`NumpyBackend.occluded_leaving`).

Random triangle soups and closed meshes (tests/strategies.py), with slivers down to a
sin² of 1e-14 and degenerate triangles, translated by up to 1e5; random pieces leaving a
triangle (p on it, own = it) toward another triangle's point or grazing its own plane, short
and long.  Every (piece, triangle) pair on which `intersect.ray_triangle` reports a hit at
0 < λ < tmax (all pairs, brute force) must be a candidate, and the grid's answer must equal
the walk's, piece by piece.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, note, settings
from hypothesis import strategies as st
from strategies import PROFILE, closed, offsets, profile, soup

from raytrace.backends import EmbreeBackend, NumpyBackend
from raytrace.intersect import ray_triangle
from raytrace.neargrid import NearGrid
from raytrace.tolerances import is_sliver


@st.composite
def triangles(draw):
    """vertices (N, 3), faces (M, 3): a few soups and closed meshes, plus slivers (a corner
    1e-7 .. 1e-2 off the opposite edge's line) and a degenerate triangle, translated."""
    objects = [draw(closed(f"c{i}")) if draw(st.booleans()) else draw(soup(f"s{i}"))
               for i in range(draw(st.integers(1, 3)))]
    tris = [o.triangles for o in objects]
    for _ in range(draw(st.integers(0, 3))):
        a, b = np.array(draw(st.lists(st.floats(-2, 2), min_size=6, max_size=6))).reshape(2, 3)
        off = 10 ** draw(st.floats(-7.0, -2.0)) * np.array([0.3, -0.7, 0.6])
        tris.append(np.array([[a, b, (a + b) / 2 + off]]))
    if draw(st.booleans()):
        tris.append(np.array([[[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]]))
    corners = np.concatenate(tris) + np.asarray(draw(offsets()))
    return corners.reshape(-1, 3), np.arange(len(corners) * 3).reshape(-1, 3)


@st.composite
def pieces(draw, corners):
    """origins (q, 3), directions (q, 3), tmax (q,), own (q,): p on triangle own, toward a
    point of another triangle (tmax 0.3 .. 1.5 of the way) or grazing own's plane (n·d̂ down
    to 1e-9), the pieces' lengths 1e-6 .. 10."""
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    q, m = 64, len(corners)
    own = rng.integers(0, m, q)
    w = rng.dirichlet([1.0, 1.0, 1.0], q)
    p = np.einsum("qk,qkj->qj", w, corners[own])
    other = rng.integers(0, m, q)
    target = np.einsum("qk,qkj->qj", rng.dirichlet([1.0, 1.0, 1.0], q), corners[other])
    d = target - p
    tmax = rng.uniform(0.3, 1.5, q)
    grazing = rng.random(q) < 0.5
    e1, e2 = corners[own, 1] - corners[own, 0], corners[own, 2] - corners[own, 0]
    n = np.cross(e1, e2)
    n /= np.where(np.linalg.norm(n, axis=1, keepdims=True) > 0,
                  np.linalg.norm(n, axis=1, keepdims=True), 1.0)
    flat = rng.normal(size=(q, 3))
    flat -= np.einsum("qj,qj->q", flat, n)[:, None] * n
    tilt = 10 ** rng.uniform(-9, -1, q) * rng.choice([-1.0, 1.0], q)
    d[grazing] = (flat + tilt[:, None] * n)[grazing]
    tmax[grazing] = 10 ** rng.uniform(-6, 1, grazing.sum()) / np.linalg.norm(d[grazing], axis=1)
    keep = np.isfinite(d).all(axis=1) & (np.abs(d).max(axis=1) > 0)
    return p[keep], d[keep], tmax[keep], own[keep]


@settings(profile(), max_examples=60 if PROFILE == "ci" else 1000)
@given(data=st.data())
def test_the_cheap_query_keeps_every_triangle_the_float64_test_meets(data):
    vertices, faces = data.draw(triangles())
    corners = vertices[faces]
    o, d, tmax, own = data.draw(pieces(corners))
    grid = NearGrid(vertices, faces, is_sliver(vertices[faces]))
    piece, tri = grid.candidates(o, d, tmax)
    lam = ray_triangle(o[:, None], d[:, None], corners[None, :, 0], corners[None, :, 1],
                       corners[None, :, 2])
    met = lam < tmax[:, None]
    kept = np.zeros_like(met)
    kept[piece, tri] = True
    note(f"{len(faces)} triangles, {len(o)} pieces, {int(met.sum())} hits, "
         f"{len(piece)} candidates")
    missed = np.argwhere(met & ~kept)
    assert len(missed) == 0, f"hits left out of the candidates (piece, triangle): {missed[:5]}"
    # numba's pairs (raytrace.nearkernels, where it loads) are numpy's, as a set
    assert _pairs(grid.candidates(o, d, tmax)) == _pairs(grid.candidates(o, d, tmax, False))
    walk = NumpyBackend(vertices, faces).occluded_leaving(o, d, tmax, own)
    assert np.array_equal(grid.occluded_leaving(NumpyBackend(vertices, faces), o, d, tmax, own),
                          walk)
    assert np.array_equal(EmbreeBackend(vertices, faces).occluded_leaving(o, d, tmax, own), walk)


def _pairs(found) -> set:
    return set(zip(*(x.tolist() for x in found)))


def test_the_query_is_empty_away_from_the_geometry_and_full_beside_it():
    """The query is cheap where it should be and not vacuous: a piece far from a unit quad
    gets no candidate, one crossing it both of its triangles (and the walk agrees)."""
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    grid = NearGrid(vertices, faces, is_sliver(vertices[faces]))
    o = np.array([[0.5, 0.5, 0.5], [0.5, 0.5, -1.0], [0.6, 0.4, -1.0]])
    d = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    tmax = np.array([0.1, 2.0, 0.5])
    piece, tri = grid.candidates(o, d, tmax)
    assert 0 not in piece and {0, 1} <= set(tri[piece == 1].tolist())
    assert grid.occluded_leaving(NumpyBackend(vertices, faces), o, d, tmax,
                                 np.full(3, -1)).tolist() == [False, True, False]


def test_cells_are_found_whether_or_not_their_table_slot_is_shared():
    """The grid finds a cell's key through a hash table, and in the sorted keys where several
    keys share a slot: with a table of 2**b slots for b = 1 (every slot shared) up to the
    default, every occupied cell's key is found at its own index, no other key is, and the
    candidates of a scene's pieces are the same pairs."""
    rng = np.random.default_rng(7)
    centres = rng.uniform(-5, 5, (3000, 1, 3)) * [1.0, 0.2, 1.0]
    sizes = rng.uniform(0.1, 20, (3000, 1, 1))
    corners = centres + rng.normal(scale=0.05, size=(3000, 3, 3)) * sizes
    vertices, faces = corners.reshape(-1, 3), np.arange(9000).reshape(-1, 3)
    grid = NearGrid(vertices, faces, is_sliver(corners))
    o = corners[:, 0] * 0.9 + corners[:, 1] * 0.1
    d = rng.normal(size=o.shape)
    tmax = 10 ** rng.uniform(-3, 0, len(o))
    expected = set(zip(*(x.tolist() for x in grid.candidates(o, d, tmax))))
    others = np.setdiff1d(grid.keys + 1, grid.keys)
    queries = rng.permutation(np.concatenate([grid.keys, others]))
    for bits in (1, 4, 8, grid._bits):
        grid._index(bits)
        if bits == 1:
            assert (grid._table == -2).all()  # every key looked for in the sorted keys
        found, at = grid._find(queries)
        assert np.array_equal(queries[found], grid.keys[at])
        assert len(found) == len(grid.keys)
        assert set(zip(*(x.tolist() for x in grid.candidates(o, d, tmax)))) == expected
        assert _pairs(grid.candidates(o, d, tmax, False)) == expected
