"""Edge topology and the multiplicity rule, on the CPU (no GL)."""

from __future__ import annotations

import numpy as np
import pytest

from shadowvol.primitives import box, sphere
from shadowvol.raster.volumes.silhouettes import (
    edge_multiplicity,
    extrude,
    side_quads,
    triangle_signs,
)
from shadowvol.raster.volumes.topology import Topology
from shadowvol.raster.volumes.builder import MAX_OPPOSITE
from shadowvol.raster.volumes.gpu import edge_records
from shadowvol.scene import DirectionalLight, PointLight


def test_closed_box_has_18_manifold_edges():
    b = box("b")
    topo = Topology.build(b.vertices, b.faces)
    assert len(topo.vertices) == 8 and len(topo.edges) == 18
    assert (topo.triangles_per_edge == 2).all()
    assert (topo.edges[:, 0] < topo.edges[:, 1]).all()


def test_exact_welding_closes_a_soup():
    """Every corner its own vertex (as seams duplicate them): welding restores the box."""
    b = box("b")
    soup_v = b.triangles.reshape(-1, 3)
    soup_f = np.arange(len(soup_v)).reshape(-1, 3)
    topo = Topology.build(soup_v, soup_f)
    assert len(topo.vertices) == 8 and len(topo.edges) == 18
    assert (topo.triangles_per_edge == 2).all()
    # welded positions are the original ones bit for bit
    np.testing.assert_array_equal(topo.vertices[topo.remap], soup_v)


def test_welding_is_exact_not_approximate():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1e-12, 0, 0]], float)
    topo = Topology.build(v, [[0, 1, 2], [3, 2, 1]])
    assert len(topo.vertices) == 4  # 1e-12 apart stays apart
    assert sorted(topo.triangles_per_edge.tolist()) == [1, 1, 1, 1, 2]


def test_open_quad_and_non_manifold_fan():
    quad = Topology.build(np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float),
                          [[0, 1, 2], [0, 2, 3]])
    assert sorted(quad.triangles_per_edge.tolist()) == [1, 1, 1, 1, 2]
    fan = Topology.build(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1.0]]),
                         [[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    a, b = sorted(fan.remap[[0, 1]])
    shared = np.flatnonzero((fan.edges == [a, b]).all(axis=1))
    assert fan.triangles_per_edge[shared].tolist() == [3]
    assert sorted(fan.inc_opposite[fan.inc_edge == shared[0]].tolist()) == \
        sorted(fan.remap[[2, 3, 4]].tolist())


def test_collapsed_triangle_adds_no_edge():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0]], float)   # vertex 3 == vertex 1
    topo = Topology.build(v, [[0, 1, 2], [0, 1, 3]])
    signs = triangle_signs(topo.vertices, topo.faces, np.array([0, 0, 5, 1.0]))
    assert signs.tolist() == [1, 0]
    assert len(topo.edges) == 3


def _direct_multiplicity(topo, light4):
    """The rule as stated: for edge (a, b), a < b, the sum over its triangles (opposite c) of
    sign(det[b - a, c - a, L - a]), one determinant per (edge, triangle)."""
    v = topo.vertices
    a, b = v[topo.edges[topo.inc_edge, 0]], v[topo.edges[topo.inc_edge, 1]]
    c = v[topo.inc_opposite]
    to_light = light4[:3] - light4[3] * a
    det = np.einsum("ij,ij->i", np.cross(b - a, c - a), to_light)
    return np.bincount(topo.inc_edge, weights=np.sign(det), minlength=len(topo.edges))


@pytest.mark.parametrize("light", [PointLight([3.0, 4.0, 2.0]), PointLight([0.1, 0.2, 0.3]),
                                   DirectionalLight([0.3, -1.0, 0.2])])
def test_multiplicity_matches_the_direct_rule(light):
    rng = np.random.default_rng(3)
    v = rng.normal(size=(30, 3))
    f = rng.integers(0, 30, size=(80, 3))
    f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])]
    topo = Topology.build(v, f)
    light4 = light.homogeneous
    signs = triangle_signs(topo.vertices, topo.faces, light4)
    np.testing.assert_array_equal(edge_multiplicity(topo, signs),
                                  _direct_multiplicity(topo, light4))


def test_winding_does_not_matter():
    s = sphere("s", [0, 0, 0], 1.0, subdivisions=2)
    flipped = s.faces.copy()
    rng = np.random.default_rng(0)
    pick = rng.random(len(flipped)) < 0.5
    flipped[pick] = flipped[pick][:, ::-1]
    light4 = PointLight([2.0, 3.0, 1.0]).homogeneous
    quads = []
    for faces in (s.faces, flipped):
        topo = Topology.build(s.vertices, faces)
        m = edge_multiplicity(topo, triangle_signs(topo.vertices, topo.faces, light4))
        q = side_quads(topo, m, light4)
        quads.append(sorted(map(tuple, q.reshape(len(q), -1).round(12).tolist())))
    assert quads[0] == quads[1] and len(quads[0]) > 0


def test_closed_convex_mesh_silhouette_is_one_loop_of_double_quads():
    """Two-sided surfaces: the lit front AND the dark back of a closed mesh cast, so on its
    silhouette both triangles add (+1 and -1 traversed in opposite directions): |m| = 2, and
    a point behind a sphere counts 2.  Every other edge cancels to 0."""
    s = sphere("s", [0, 0, 0], 1.0, subdivisions=2)
    topo = Topology.build(s.vertices, s.faces)
    light4 = PointLight([0.3, 4.0, 0.5]).homogeneous
    m = edge_multiplicity(topo, triangle_signs(topo.vertices, topo.faces, light4))
    assert set(np.abs(m).tolist()) == {0, 2}
    sil = topo.edges[m != 0]
    # every silhouette vertex is on exactly two silhouette edges: a closed loop
    assert (np.bincount(sil.reshape(-1))[np.unique(sil)] == 2).all()


def test_open_quad_emits_its_whole_border():
    topo = Topology.build(np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float),
                          [[0, 1, 2], [0, 2, 3]])
    light4 = PointLight([0.5, 0.5, 3.0]).homogeneous
    m = edge_multiplicity(topo, triangle_signs(topo.vertices, topo.faces, light4))
    border = topo.triangles_per_edge == 1
    assert (np.abs(m[border]) == 1).all() and (m[~border] == 0).all()


def test_fan_multiplicity_counts_all_three_triangles():
    """Three triangles on one edge, all on the light's same side of it, wound every which way:
    the shared edge carries multiplicity +-3 or +-1 exactly as their signs add up."""
    v = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0.1], [0.5, -1, 0.2], [0.5, 0.1, 1.0]])
    topo = Topology.build(v, [[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    light4 = PointLight([0.5, 0.2, 5.0]).homogeneous
    signs = triangle_signs(topo.vertices, topo.faces, light4)
    m = edge_multiplicity(topo, signs)
    shared = np.flatnonzero((topo.edges == sorted(topo.remap[[0, 1]])).all(axis=1))[0]
    np.testing.assert_array_equal(m, _direct_multiplicity(topo, light4))
    assert abs(m[shared]) == 1  # two contributions cancel, one remains


def test_side_quads_extrude_away_from_the_light():
    topo = Topology.build(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float), [[0, 1, 2]])
    light4 = PointLight([0.2, 0.2, 2.0]).homogeneous
    m = edge_multiplicity(topo, triangle_signs(topo.vertices, topo.faces, light4))
    q = side_quads(topo, m, light4)
    assert q.shape == (3, 4, 4)
    assert (q[:, :2, 3] == 1).all() and (q[:, 2:, 3] == 0).all()
    # the far corners point from the light through the near corners, and pair up with them
    np.testing.assert_allclose(q[:, 2], extrude(q[:, 1, :3], light4))
    np.testing.assert_allclose(q[:, 3], extrude(q[:, 0, :3], light4))


def test_edge_records_split_many_opposite_vertices():
    """An edge on 2 * MAX_OPPOSITE + 1 triangles takes three records that hold them all."""
    n = 2 * MAX_OPPOSITE + 1
    ang = np.linspace(0, 2 * np.pi, n, endpoint=False)
    v = np.concatenate([[[0, 0, 0], [1, 0, 0]],
                        np.stack([np.full(n, 0.5), np.cos(ang), np.sin(ang)], axis=1)])
    f = np.stack([np.zeros(n, int), np.ones(n, int), np.arange(2, n + 2)], axis=1)
    topo = Topology.build(v, f)
    rec = edge_records(topo)
    shared = (np.abs(rec["a"] - v[0]).sum(axis=1) + np.abs(rec["b"] - v[1]).sum(axis=1)) == 0
    assert shared.sum() == 3 and rec["count"][shared].tolist() == [4, 4, 1]
    held = rec["c"][shared].reshape(-1, 3)[:n]
    np.testing.assert_array_equal(np.sort(held, axis=0), np.sort(v[2:].astype(np.float32),
                                                                 axis=0))
    assert rec["count"].sum() == len(topo.inc_edge)
