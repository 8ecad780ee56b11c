"""Radiosity: meshing, form factors (row sums, reciprocity, an analytic value), the furnace,
the display, and agreement with the path tracer on the diffuse Cornell box."""

from __future__ import annotations

import math

import numpy as np
import pytest
from builders import (
    PT_RADIOSITY_RELATIVE,
    RADIOSITY_TOL,
    cornell,
    facing_inside,
    furnace,
    z_limit,
)

from raytrace import radiosity
from raytrace.pathtrace import PathWorld, radiance_leaving
from shadowvol.primitives import plane
from shadowvol.scene import Camera, Material, Scene


def test_mesh_keeps_the_area_and_bounds_the_edges():
    scene = cornell(8)
    vertices, faces, _ = scene.triangles()
    c = vertices[faces]
    area = 0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1).sum()
    longest = np.linalg.norm(c - np.roll(c, 1, axis=1), axis=2).max()
    for level in (0, 2):
        mesh = radiosity.mesh_patches(scene, level)
        m = mesh.vertices[mesh.faces]
        assert math.isclose(mesh.area.sum(), area, rel_tol=1e-12)
        assert np.linalg.norm(m - np.roll(m, 1, axis=1), axis=2).max() <= \
            longest / 2 ** level * (1 + 1e-12)
    assert radiosity.mesh_patches(scene, 2).triangles > 8 * len(faces)


def test_furnace_box_converges_to_emission_over_one_minus_albedo():
    rho, emitted = 0.6, 0.5
    scene = furnace([rho] * 3, [emitted] * 3)
    sol = radiosity.solve(scene, level=2, rays_per_patch=64, tol=RADIOSITY_TOL)
    F, _ = radiosity.form_factors(scene, sol.mesh, rays_per_patch=64)
    inside = _inside_patches(sol.mesh)
    # a closed box: every ray from an inner face hits an inner face; outer faces see nothing
    np.testing.assert_allclose(np.asarray(F.sum(axis=1)).ravel(),
                               np.where(inside, 1.0, 0.0), atol=1e-12)
    expected = emitted / (1.0 - rho)
    assert sol.unshot <= RADIOSITY_TOL
    np.testing.assert_allclose(sol.radiance[inside], expected,
                               rtol=RADIOSITY_TOL / (1.0 - rho) * 2)
    np.testing.assert_allclose(sol.radiance[~inside], emitted)
    # seen from inside, flat and interpolated displays are the same constant
    for smooth in (False, True):
        image = radiosity.display(scene, sol, interpolate=smooth)
        np.testing.assert_allclose(image, expected, rtol=RADIOSITY_TOL / (1.0 - rho) * 2)


def _inside_patches(mesh) -> np.ndarray:
    """(2T,) bool: patches of the furnace cube (centred at the origin) facing its centre."""
    centres = np.concatenate([mesh.vertices[mesh.faces].mean(axis=1)] * 2)
    return (mesh.patch_normal() * -centres).sum(axis=1) > 0.0


def test_form_factor_rows_never_exceed_one():
    scene = cornell(8)
    mesh = radiosity.mesh_patches(scene, 1)
    F, rays = radiosity.form_factors(scene, mesh, rays_per_patch=128)
    assert rays == mesh.patches * 128
    sums = np.asarray(F.sum(axis=1)).ravel()
    assert sums.max() <= 1.0 + 1e-12
    # the box is open at the front (the camera looks in): inner faces lose a little, not all
    inner = sums > 0.5
    assert inner.sum() >= mesh.triangles * 0.9
    assert 0.6 < np.median(sums[inner]) < 1.0


def test_reciprocity_between_objects():
    """A_I F_IJ = A_J F_JI for every pair of Cornell objects (their camera-side faces), z-test
    on the ray counts (binomial variance), false alarm FALSE_ALARM over all pairs."""
    scene = cornell(8)
    K = 2048
    mesh = radiosity.mesh_patches(scene, 1)
    F, _ = radiosity.form_factors(scene, mesh, rays_per_patch=K, seed=5)
    T = mesh.triangles
    centres = mesh.vertices[mesh.faces].mean(axis=1)
    group = np.full(mesh.patches, -1)
    for k, obj in enumerate(scene.objects):
        sel = np.flatnonzero(mesh.tri_object == k)
        n = facing_inside(obj, centres[sel], mesh.normal[sel])
        front = (n * mesh.normal[sel]).sum(axis=1) > 0.0
        group[np.where(front, sel, sel + T)] = k
    G = len(scene.objects)
    area = mesh.patch_area()
    coo = F.tocoo()
    keep = (group[coo.row] >= 0) & (group[coo.col] >= 0)
    i, j, f = group[coo.row[keep]], group[coo.col[keep]], coo.data[keep]
    a = area[coo.row[keep]]
    flow = np.zeros((G, G))  # A_I F_IJ
    var = np.zeros((G, G))
    np.add.at(flow, (i, j), a * f)
    np.add.at(var, (i, j), a * a * f * (1.0 - f) / K)
    upper = np.triu_indices(G, 1)
    diff = (flow - flow.T)[upper]
    sigma = np.sqrt((var + var.T)[upper])
    seen = flow[upper] > 0.0
    z = diff[seen] / sigma[seen]
    assert seen.sum() >= 15
    assert np.abs(z).max() < z_limit(len(z)), z


def test_parallel_squares_match_the_analytic_form_factor():
    """Two unit squares facing each other at distance 1: F = 0.19982 (Howell's catalogue, C-11)."""
    X = Y = 1.0
    analytic = 2.0 / (math.pi * X * Y) * (
        math.log(math.sqrt((1 + X * X) * (1 + Y * Y) / (1 + X * X + Y * Y)))
        + X * math.sqrt(1 + Y * Y) * math.atan(X / math.sqrt(1 + Y * Y))
        + Y * math.sqrt(1 + X * X) * math.atan(Y / math.sqrt(1 + X * X))
        - X * math.atan(X) - Y * math.atan(Y))
    assert abs(analytic - 0.19982) < 1e-4
    m = Material(diffuse=[0.5] * 3, specular=[0, 0, 0])
    scene = Scene(camera=Camera(eye=[0, 0.5, 5], target=[0, 0.5, 0]), lights=[],
                  objects=[plane("bottom", point=[0, 0, 0], normal=[0, 1, 0], size=[1, 1],
                                 material=m),
                           plane("top", point=[0, 1, 0], normal=[0, -1, 0], size=[1, 1],
                                 material=m)], width=8, height=8)
    K = 40000
    mesh = radiosity.mesh_patches(scene, 0)
    F, _ = radiosity.form_factors(scene, mesh, rays_per_patch=K, seed=2)
    T = mesh.triangles
    up = mesh.patch_normal()[:, 1] > 0.5  # bottom's upper face, and top's upper face
    bottom = np.flatnonzero(up & (mesh.patch_object() == 0))
    top_facing_down = np.flatnonzero(~up & (mesh.patch_object() == 1))
    assert len(bottom) == 2 and len(top_facing_down) == 2 and T == 4
    a = mesh.patch_area()[bottom]
    estimate = (a * np.asarray(F[bottom][:, top_facing_down].sum(axis=1)).ravel()).sum() / a.sum()
    sigma = math.sqrt(analytic * (1 - analytic) / (K * len(bottom)))
    assert abs(estimate - analytic) < z_limit(1) * sigma, (estimate, analytic)


def test_path_tracing_and_radiosity_agree_on_the_diffuse_cornell_box(path_shading):
    """Area-averaged radiance of every object (its camera-side face): radiosity at level 3 (2048 rays a patch)
    against 20000 path-traced points per object, within z_limit standard errors plus
    PT_RADIOSITY_RELATIVE."""
    scene = cornell(8)
    sol = radiosity.solve(scene, level=3, rays_per_patch=2048, tol=1e-5, shots=8, seed=1)
    mesh, T = sol.mesh, sol.mesh.triangles
    centres = mesh.vertices[mesh.faces].mean(axis=1)
    world = PathWorld(scene)
    rng = np.random.default_rng(4)
    M = 20000
    checked = []
    for k, obj in enumerate(scene.objects):
        if obj.material.emission.any():
            continue
        sel = np.flatnonzero(mesh.tri_object == k)
        n = facing_inside(obj, centres[sel], mesh.normal[sel])
        patch = np.where((n * mesh.normal[sel]).sum(axis=1) > 0.0, sel, sel + T)
        a = mesh.area[sel]
        rad = (a[:, None] * sol.radiance[patch]).sum(axis=0) / a.sum()
        tri = obj.triangles
        cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        area = np.linalg.norm(cross, axis=1)
        j = rng.choice(len(tri), M, p=area / area.sum())
        r, u = np.sqrt(rng.random(M)), rng.random(M)
        c = tri[j]
        p = ((1 - r)[:, None] * c[:, 0] + (r * (1 - u))[:, None] * c[:, 1]
             + (r * u)[:, None] * c[:, 2])
        normals = facing_inside(obj, p, cross[j] / area[j, None])
        L, _ = radiance_leaving(world, p, normals, rng)
        pt, se = L.mean(axis=0), L.std(axis=0) / math.sqrt(M)
        checked.append((obj.name, rad, pt, se))
    z = z_limit(3 * len(checked))
    bad = [(name, rad, pt) for name, rad, pt, se in checked
           if (np.abs(rad - pt) > z * se + PT_RADIOSITY_RELATIVE * pt).any()]
    assert len(checked) == 7
    assert not bad, bad


@pytest.mark.parametrize("level", [-1, 1.5, True])
def test_bad_level_is_refused(level):
    with pytest.raises(ValueError, match="level"):
        radiosity.mesh_patches(cornell(8), level)


def test_max_edge_meshes_to_a_size():
    scene = cornell(8)
    coarse = radiosity.mesh_patches(scene, max_edge=200.0)
    fine = radiosity.mesh_patches(scene, max_edge=100.0)
    c = fine.vertices[fine.faces]
    assert np.linalg.norm(c - np.roll(c, 1, axis=1), axis=2).max() <= 100.0
    assert 3 * coarse.triangles < fine.triangles
    with pytest.raises(ValueError, match="max_edge"):
        radiosity.mesh_patches(scene, max_edge=0.0)
