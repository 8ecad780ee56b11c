"""The reference masks (Embree, float32 rays) against an exact float64 brute-force check.

`exact_masks` is the definition of CONVENTIONS.md's "lit" written as plainly as possible, for
tests only: for every pixel centre, the nearest triangle along the float64 ray (every triangle
tried, no BVH), then for every light the segment from that point to the light tested against
every other triangle (Möller–Trumbore in float64, the visible triangle skipped, nothing moved
off the segment).  It is slow (pixels x triangles), so it runs on small scenes and crops.

The scenes are the ones where the old reference (shadow rays started 1e-4 of the scene size off
the surface along the normal) was wrong away from shadow edges: a wall lit at 2 and 5 degrees
(the edge moved by offset / tan(elevation)), concave creases (the moved start escaped the
neighbouring face that blocks the segment).  The real-mesh crop lives in test_real_meshes.py
(it needs ../shared/models).

The checker itself lives in tests/exact.py (shared with the large-world tests).  Budget
(`check_exact`): zero mismatches farther than one pixel from a mask edge
(shadowvol.compare.maskdiff), and at most EXACT_EDGE_BUDGET of the pixels in all (float32 picks the
other side of an edge for rays within ~1e-7 of it).
"""

from __future__ import annotations

import numpy as np
import pytest
from exact import check_exact

import raytrace
from raytrace.backends import make_backend
from raytrace.tolerances import error_weight, shadow_height
from shadowvol.primitives import Transform, box, mesh, plane
from shadowvol.scene import Camera, DirectionalLight, PointLight, Scene, SpotLight

# ---- scenes -----------------------------------------------------------------------------------

def grazing_wall(elevation: float, size=(320, 240)) -> Scene:
    """A 200 x 200 wall at z = -80 with a slab in front of it, lit from `elevation` degrees
    above the wall's plane (the case where a normal offset moves the edge by offset/tan)."""
    e = np.radians(elevation)
    d = np.array([np.cos(e) * 0.7, 0.7, -np.sin(e)])
    return Scene(camera=Camera(eye=[0, 0, 10], target=[0, 0, -80], near=0.05, fov_y=20),
                 objects=[plane("wall", point=[0, 0, -80], normal=[0, 0, 1], size=[200, 200]),
                          box("slab", [0, 0, -79.0], [20, 20, 0.5])],
                 lights=[DirectionalLight(d)], width=size[0], height=size[1])


def crease(angle: float, light, rotation=(0.0, 0.0, 0.0), size=(128, 96)) -> Scene:
    """A concave crease: a 3 x 4 floor and a 1 x 4 face hinged on the z axis at `angle`
    degrees from it (rotated by `rotation`, so that nothing is axis-aligned), the light behind
    the face: the face shadows the floor from the crease to a line beyond it."""
    a = np.radians(angle)
    rot = Transform(rotation=rotation)
    floor = np.array([[0, 0, -2], [3, 0, -2], [3, 0, 2], [0, 0, 2]], float)
    up = np.array([np.cos(a), np.sin(a), 0.0])
    face = np.array([[0, 0, -2], [0, 0, 2], up + [0, 0, 2], up + [0, 0, -2]], float)
    quads = [[0, 1, 2], [0, 2, 3]]
    eye = rot.points(np.array([[2.6, 1.6, 2.4]]))[0]
    target = rot.points(np.array([[0.6, 0.2, 0.0]]))[0]
    return Scene(camera=Camera(eye=eye, target=target, fov_y=50, near=0.05),
                 objects=[mesh("floor", rot.points(floor), quads),
                          mesh("face", rot.points(face), quads)],
                 lights=[light(rot)], width=size[0], height=size[1])


def crease_close_up(angle: float, rotation=(0.0, 0.0, 0.0), size=(96, 72)) -> Scene:
    """The crease of `crease` seen through a 0.1-degree lens (a pixel is ~7e-5 wide), one light
    inside the crease (everything near it lit) and one behind the face (the floor near the
    crease shadowed), the eye inside the crease too: a start point moved off the surface along
    the normal crosses the other face here and shadows a band along the crease."""
    a = np.radians(angle)
    rot = Transform(rotation=rotation)
    inside = rot.points(np.array([[np.cos(a / 2) * 2, np.sin(a / 2) * 2, -0.5]]))[0]
    behind = rot.points(np.array([[-np.sin(a) * 2, np.cos(a) * 2, 0.3]]))[0]
    scene = crease(angle, lambda r: PointLight(inside), rotation, size)
    return scene.replace(
        lights=(PointLight(inside), PointLight(behind)),
        camera=Camera(eye=rot.points(np.array([[np.cos(a / 2) * 2, np.sin(a / 2) * 2, 2.0]]))[0],
                      target=rot.points(np.array([[0.0, 0.0, 0.3]]))[0], fov_y=0.1, near=0.05))


@pytest.mark.parametrize("rotation", [(0.0, 0.0, 0.0), (17.0, 31.0, -9.0)])
def test_crease_close_up_matches_exact(request, rotation):
    """Budget: one pixel row along the crease (96 pixels).  At this magnification a pixel is
    ~600 float32 spacings and the margin `shadow_height` ~130 of them, so the floor points
    within the margin of the face (a sliver along the crease, under a pixel wide) are lit by
    the light behind the face: the contact shadow the margin gives up, by design.  The old
    normal offset got 511 and 149 interior mismatches here."""
    check_exact(request, crease_close_up(20.0, rotation), budget=96)


@pytest.mark.parametrize("elevation", [2.0, 5.0])
def test_grazing_wall_matches_exact(request, elevation):
    check_exact(request, grazing_wall(elevation))


CREASES = {
    # a face leaning over the floor at 60 degrees, the point light behind it
    "60deg point": (60.0, lambda r: PointLight(r.points(np.array([[-1.0, 2.5, 0.3]]))[0])),
    # an open 120-degree crease, the light grazing in over the face's top edge
    "120deg directional": (120.0, lambda r: DirectionalLight(
        r.vectors(np.array([[0.9, -0.35, 0.1]]))[0])),
    # a right angle, a spot light behind the face
    "90deg spot": (90.0, lambda r: SpotLight(r.points(np.array([[-0.8, 1.5, 0.0]]))[0],
                                             r.vectors(np.array([[1.0, -1.0, 0.0]]))[0], 60)),
}


@pytest.mark.parametrize("rotation", [(0.0, 0.0, 0.0), (17.0, 31.0, -9.0)])
@pytest.mark.parametrize("name", sorted(CREASES))
def test_concave_crease_matches_exact(request, name, rotation):
    angle, light = CREASES[name]
    check_exact(request, crease(angle, light, rotation))


def test_numpy_backend_matches_exact_too(request):
    """The same margins on the float64 numpy backend."""
    scene = crease(60.0, CREASES["60deg point"][1], (17.0, 31.0, -9.0), size=(64, 48))
    check_exact(request, scene, reference=raytrace.shadow_masks(scene, "numpy"))


# ---- the margin itself ------------------------------------------------------------------------

@pytest.mark.parametrize("backend", ["embree", "numpy"])
@pytest.mark.parametrize("centre", [(0.0, 0.0, 0.0), (900.0, -300.0, 500.0), (3e4, 1e4, -2e4)])
def test_a_shadow_ray_never_hits_the_triangle_it_leaves(backend, centre):
    """Seeded property of the margin: from a random point of a random triangle, the shadow ray
    started on its own line at height `shadow_height` above the triangle (t = h / (n·l)),
    toward directions down to 1e-6 rad of grazing, misses that triangle and its coplanar
    copy with other corners (a second triangle of the same plane overlapping it)."""
    rng = np.random.default_rng(12)
    m, n_rays = 343, 20000
    # one triangle per cell of a 7 x 7 x 7 grid, 10 apart: a ray of length <= 2 meets only
    # its own triangle and that triangle's partner
    cells = np.stack(np.meshgrid(*[np.arange(-3, 4)] * 3), axis=-1).reshape(-1, 3)
    a = np.asarray(centre) + 10.0 * cells + rng.normal(scale=0.3, size=(m, 3))
    e1, e2 = rng.normal(scale=0.3, size=(2, m, 3))
    tri = np.stack([a, a + e1, a + e2], axis=1)
    # each triangle's coplanar partner: the same plane, corners moved within it
    partner = tri + 0.3 * (rng.random((m, 3, 1)) - 0.5) * (e1 - e2)[:, None]
    v = np.concatenate([tri, partner]).reshape(-1, 3)
    tracer = make_backend(backend, v, np.arange(len(v)).reshape(-1, 3))
    k = rng.integers(0, m, n_rays)
    bary = rng.dirichlet([1, 1, 1], n_rays)
    p = np.einsum("nk,nkj->nj", bary, tri[k])
    normal = np.cross(e1, e2)[k]
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    normal *= rng.choice([-1.0, 1.0], (n_rays, 1))
    d = rng.normal(size=(n_rays, 3))
    d -= np.einsum("ij,ij->i", d, normal)[:, None] * normal
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    elevation = np.where(rng.random(n_rays) < 0.3, 10 ** rng.uniform(-6, -3, n_rays),
                         rng.uniform(0, np.pi / 2, n_rays))
    d = np.cos(elevation)[:, None] * d + np.sin(elevation)[:, None] * normal
    # the masks' bound: the triangle's error weight plus p's coordinates weighted by |n|
    weight = error_weight(normal, tri[k]) + np.einsum("ij,ij->i", np.abs(normal), np.abs(p))
    height = shadow_height(weight)
    start = p + (height / np.einsum("ij,ij->i", normal, d))[:, None] * d
    hit = tracer.occluded(start, d, 2.0)
    assert not hit.any(), f"{hit.sum()} of {n_rays} shadow rays hit the triangle they left"


@pytest.mark.parametrize("offset", [0.0, 1e4])
def test_no_self_shadow_on_a_plane_lit_at_grazing_angles(offset):
    """A big plane (two triangles, far from the origin in the second case) lit at 0.05 to 3
    degrees: every pixel that sees it is lit, by every light."""
    lights = [DirectionalLight([np.cos(np.radians(e)), -np.sin(np.radians(e)), 0.3])
              for e in (0.05, 0.5, 3.0)]
    lights.append(PointLight([offset - 30.0, 0.02, offset + 1.0]))
    scene = Scene(camera=Camera(eye=[offset, 3.0, offset + 6.0], target=[offset, 0, offset]),
                  objects=[plane("floor", point=[offset, 0, offset], size=[40, 40])],
                  lights=lights, width=96, height=72)
    lit, cov = raytrace.shadow_masks(scene)
    assert cov.mean() > 0.4
    for i in range(len(lights)):
        assert np.array_equal(lit[i], cov), f"light {i}: {(cov & ~lit[i]).sum()} self-shadowed"
