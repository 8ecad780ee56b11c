"""A grazing light and an occluder of the same mesh a little way along the shadow ray (issue 31).

The shadow ray once started at p + (height / n·l)·l: at n·l̂ = 1e-3 that is a thousand margin
heights along the segment, and a wall of the same mesh crossing it there was skipped (a lit
band behind the wall's foot).  Here a floor and a wall through it (one mesh) are lit at n·l̂
of 1e-4, 1e-3 and 0.03 by a point light whose segment crosses the wall 0.3-5 % of the way,
by a directional light and by a rect light's samples, and the masks and counts are checked
against the float64 brute force (tests/exact.py: all triangles, only p's own skipped).  The
ground truth (`raytrace.ground_truth`) rides the same near pieces: its lit, counts and
casters, with the wall an object of its own, against the same walk (`exact_casters`).
"""

from __future__ import annotations

import numpy as np
import pytest
from exact import check_counts, check_exact, exact_casters

import raytrace
from raytrace.soft import lit_counts
from raytrace.tolerances import shadow_height
from shadowvol.compare.maskdiff import edge_pixels
from shadowvol.primitives import mesh
from shadowvol.scene import AreaLight, Camera, DirectionalLight, PointLight, Scene


def wall_foot(sin_elevation: float, kind: str, offset=(0.0, 0.0, 0.0), size=(64, 48)) -> Scene:
    """A floor (y = 0) and a wall x = 0 through it, one mesh, seen from 1 above the floor
    where the old lift skipped the wall: a window of 4 lift lengths b across, the wall's
    shadow on x < 0 and light on x > 0.  The light (kind: point, directional or rect) is at
    elevation asin(sin_elevation) beyond the wall, a point or rect light at distance b / 0.02
    (the wall 0-5 % along the segments of the pixels within b of it)."""
    b = float(shadow_height(2.0)) / sin_elevation  # the old lift's length, eye 1 above the floor
    e = np.arcsin(sin_elevation)
    dist = b / 0.02
    far, wide, tall = 2 * dist, 4 * b, 2 * dist * sin_elevation + b
    o = np.asarray(offset, float)
    floor = [[-wide, 0, -wide], [far, 0, -wide], [far, 0, wide], [-wide, 0, wide]]
    wall = [[0, -tall, -wide], [0, tall, -wide], [0, tall, wide], [0, -tall, wide]]
    vertices = np.array(floor + wall, float) + o
    faces = [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7]]
    toward = np.array([np.cos(e), np.sin(e), 0.0])
    if kind == "point":
        light = PointLight(o + dist * toward)
    elif kind == "directional":
        light = DirectionalLight(-toward)
    else:
        light = AreaLight("rect", o + dist * toward, normal=[-1.0, 0.0, 0.0],
                          size=[2 * b, dist * sin_elevation], samples=8)
    eye = o + [-b, 1.0, 0.0]
    camera = Camera(eye=eye, target=eye - [0.0, 1.0, 0.0], up=[1.0, 0.0, 0.0],
                    fov_y=float(np.degrees(2 * np.arctan(1.5 * b))), near=0.05)
    return Scene(camera=camera, objects=[mesh("ground", vertices, np.array(faces))],
                 lights=[light], width=size[0], height=size[1])


@pytest.mark.parametrize("offset", [(0.0, 0.0, 0.0), (3e4, -1e4, 2e4)])
@pytest.mark.parametrize("kind", ["point", "directional"])
@pytest.mark.parametrize("sin_elevation", [1e-4, 1e-3, 0.03])
def test_hard_light_is_blocked_by_the_wall_it_grazes(request, sin_elevation, kind, offset):
    scene = wall_foot(sin_elevation, kind, offset)
    report = check_exact(request, scene)
    assert report[1]["interior"] == 0


@pytest.mark.parametrize("backend", ["embree", "numpy"])
@pytest.mark.parametrize("sin_elevation", [1e-4, 1e-3, 0.03])
def test_area_light_samples_are_blocked_by_the_wall_they_graze(request, sin_elevation,
                                                               backend):
    scene = wall_foot(sin_elevation, "rect")
    count, _ = lit_counts(scene, backend)
    check_counts(request, scene, count)
    # the scene tests something: samples blocked behind the wall, all of them lit before it
    assert count[0].min() == 0 and count[0].max() == 8


def wall_apart(scene: Scene, before: int = 69) -> Scene:
    """`wall_foot`'s scene with the floor object 0 and the wall object before + 1 (69: its
    casters bit in the second word), the objects between single triangles far below the
    floor, out of every segment's way."""
    ground = scene.objects[0]
    v, f = ground.vertices, ground.faces
    low = v[:3] - [0.0, 1e3, 0.0]
    spare = [mesh(f"spare{k}", low + [0.0, -k, 0.0], np.array([[0, 1, 2]]))
             for k in range(before)]
    return scene.replace(objects=[mesh("floor", v, f[:2])] + spare + [mesh("wall", v, f[2:])])


@pytest.mark.parametrize("backend", ["embree", "numpy"])
@pytest.mark.parametrize("kind", ["point", "directional", "rect"])
def test_ground_truth_counts_and_casters_see_the_wall_they_graze(kind, backend):
    scene = wall_apart(wall_foot(1e-3, kind, (3e4, -1e4, 2e4), size=(32, 24)))
    truth = raytrace.ground_truth(scene, outputs=("facing_count", "casters"), backend=backend)
    lit, _ = raytrace.shadow_masks(scene, backend)
    np.testing.assert_array_equal(truth.lit, lit)
    want = exact_casters(scene)
    wall = len(scene.objects) - 1
    assert truth.casters.shape[-1] == 2
    for i in range(len(scene.lights)):
        got_count, want_count = truth.lit_count[i], want["lit_count"][i]
        edges = edge_pixels(got_count == got_count.max()) | edge_pixels(want_count == 0)
        assert not ((got_count != want_count) & ~edges).any()
        bit = np.uint64(1) << np.uint64(wall % 64)
        got, exact = (truth.casters[i, ..., 1] & bit) > 0, (want["casters"][i, ..., 1] & bit) > 0
        assert not ((got != exact) & ~(edge_pixels(got) | edge_pixels(exact))).any()
        assert exact.sum() > 100  # the wall shadows the floor behind it
        np.testing.assert_array_equal(truth.casters[i, ..., 0], 0)  # nothing else casts
    np.testing.assert_array_equal(truth.casters.any(-1), truth.lit_count < truth.facing_count)
