"""`shadowvol.from_trimesh`: a trimesh.Scene with its camera and lights -> our Scene.

The camera is trimesh's, taken as its matrices (K and camera_to_world written back as trimesh
has them), and checked against trimesh's own camera rays cast with trimesh's own float64
ray-triangle intersector: the object each ray meets first is the object our ray tracer sees at
that pixel, away from the objects' edges.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from trimesh.scene import lighting

import raytrace
import shadowvol
from shadowvol.cameras import calibration
from shadowvol.compare.maskdiff import edge_pixels
from shadowvol.scene import DirectionalLight, PointLight, SceneError, SpotLight


def _scene(resolution=(80, 60), fov=(62.0, 41.0)) -> trimesh.Scene:
    """A floor and two boxes, seen by a turned camera with non-square pixels (fov x and y
    chosen apart from the aspect ratio)."""
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.creation.box([8.0, 0.1, 8.0]), node_name="floor",
                       transform=trimesh.transformations.translation_matrix([0, -0.05, 0]))
    crate = trimesh.creation.box([1.0, 1.0, 1.0])
    crate.visual = trimesh.visual.TextureVisuals(
        material=trimesh.visual.material.PBRMaterial(baseColorFactor=[255, 0, 0, 255]))
    scene.add_geometry(crate, node_name="crate",
                       transform=trimesh.transformations.translation_matrix([0.3, 0.5, 0]))
    tall = trimesh.transformations.rotation_matrix(0.4, [0, 1, 0])
    tall[:3, 3] = [-1.2, 0.8, -0.6]
    scene.add_geometry(trimesh.creation.box([0.5, 1.6, 0.5]), node_name="post",
                       transform=tall)
    scene.set_camera(angles=[-0.55, 0.35, 0.0], distance=7.0, center=[0, 0.5, 0],
                     resolution=resolution, fov=fov)
    return scene


def _first_hits(o: np.ndarray, d: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """(n,) index of the triangle each ray o + t d (n, 3) meets first (t > 0), -1 for none:
    Möller-Trumbore in float64, every triangle of tri (m, 3, 3) tried (trimesh's intersector
    needs rtree, not a dependency)."""
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    p = np.cross(d[:, None], e2[None])
    det = np.einsum("nmk,mk->nm", p, e1)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = o[:, None] - tri[None, :, 0]
        u = np.einsum("nmk,nmk->nm", s, p) / det
        q = np.cross(s, e1[None])
        v = np.einsum("nk,nmk->nm", d, q) / det
        t = np.einsum("mk,nmk->nm", e2, q) / det
    t = np.where((det != 0) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0), t, np.inf)
    return np.where(np.isfinite(t).any(axis=1), t.argmin(axis=1), -1)


def test_the_camera_is_trimeshs_matrices():
    tm = _scene()
    scene = shadowvol.from_trimesh(tm)
    assert (scene.width, scene.height) == (80, 60)
    cal = calibration(scene)
    np.testing.assert_array_equal(cal.K, tm.camera.K)
    np.testing.assert_array_equal(cal.camera_to_world, tm.camera_transform)
    assert scene.camera.fx != scene.camera.fy
    assert scene.camera.near == tm.camera.z_near
    assert [o.name for o in scene.objects] == ["floor", "crate", "post"]
    np.testing.assert_array_equal(scene.objects[1].material.diffuse, [1.0, 0.0, 0.0])
    for obj, node in zip(scene.objects, ("floor", "crate", "post")):
        matrix, name = tm.graph[node]
        mesh = tm.geometry[name]
        np.testing.assert_allclose(obj.vertices, trimesh.transform_points(mesh.vertices, matrix),
                                   rtol=0, atol=1e-12)


def test_trimeshs_own_rays_meet_what_the_ray_tracer_sees():
    tm = _scene()
    scene = shadowvol.from_trimesh(tm)
    truth = raytrace.ground_truth(scene, outputs=("object_id",))
    origins, vectors, pixels = tm.camera_rays()
    vertices, faces, ids = scene.triangles()
    hit = _first_hits(origins, vectors, vertices[faces])
    theirs = np.zeros((scene.height, scene.width), np.uint16)
    rows = scene.height - 1 - pixels[:, 1]   # trimesh counts pixel rows from the bottom
    theirs[rows, pixels[:, 0]] = np.where(hit >= 0, ids[hit] + 1, 0)
    assert len(np.unique(theirs)) == 4      # background and the three objects
    differ = truth.object_id != theirs
    near_edge = np.zeros_like(differ)
    for k in range(4):
        near_edge |= edge_pixels(theirs == k)
    assert not (differ & ~near_edge).any(), np.argwhere(differ & ~near_edge)[:5]
    assert differ.sum() <= 0.01 * differ.size


def test_lights_are_the_scenes_own_else_one_default():
    tm = _scene()
    scene = shadowvol.from_trimesh(tm)
    assert not hasattr(tm, "_lights") or tm._lights is None    # trimesh's were not made
    (light,) = scene.lights
    assert isinstance(light, DirectionalLight)
    np.testing.assert_allclose(light.direction @ tm.camera_transform[:3, 1], -0.86, atol=0.01)
    sun = lighting.DirectionalLight(name="sun", color=[255, 255, 204, 255], intensity=0.5)
    lamp = lighting.PointLight(name="lamp", intensity=2.0)
    spot = lighting.SpotLight(name="spot", outerConeAngle=math.radians(25))
    tm.lights = [sun, lamp, spot]
    tm.graph["sun"] = trimesh.transformations.rotation_matrix(-math.pi / 2, [1, 0, 0])
    tm.graph["lamp"] = trimesh.transformations.translation_matrix([1, 4, 1])
    aim = trimesh.transformations.rotation_matrix(-math.pi / 2, [1, 0, 0])
    aim[:3, 3] = [0, 5, 0]
    tm.graph["spot"] = aim
    sun_light, lamp_light, spot_light = shadowvol.from_trimesh(tm).lights
    assert isinstance(sun_light, DirectionalLight) and isinstance(lamp_light, PointLight)
    assert isinstance(spot_light, SpotLight)
    np.testing.assert_allclose(sun_light.direction, [0, -1, 0], atol=1e-12)
    np.testing.assert_allclose(sun_light.color, [1.0, 1.0, 0.8])
    assert sun_light.intensity == 0.5 and lamp_light.intensity == 2.0
    np.testing.assert_array_equal(lamp_light.position, [1, 4, 1])
    np.testing.assert_allclose(spot_light.direction, [0, -1, 0], atol=1e-12)
    assert spot_light.cone_angle == pytest.approx(25.0)


def test_a_new_size_scales_the_camera_and_bad_cameras_are_refused():
    tm = _scene()
    big = shadowvol.from_trimesh(tm, width=160, height=120)
    np.testing.assert_array_equal(calibration(big).K[:2], 2 * tm.camera.K[:2])
    bare = trimesh.Scene(trimesh.creation.box())
    with pytest.raises(SceneError, match="camera: the trimesh scene has no camera"):
        shadowvol.from_trimesh(bare)
    assert not bare.has_camera                                  # none was made up
    scaled = _scene()
    scaled.camera_transform = scaled.camera_transform @ np.diag([2.0, 2.0, 2.0, 1.0])
    with pytest.raises(SceneError, match="camera.camera_to_world: not rigid"):
        shadowvol.from_trimesh(scaled)
