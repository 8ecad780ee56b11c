"""Cameras given by matrices in the ray tracer (docs/CONVENTIONS.md, "Camera matrices").

- The K and camera_to_world a frame writes, read back as its camera (a scene file's `fx`, `fy`,
  `cx`, `cy`, `camera_to_world`), give the same file again bit for bit: masks, every ground
  truth output and the matrices themselves.
- Independent of the renderers: points placed at known pixels by K and camera_to_world in
  float64 (non-square pixels, an off-centre principal point, a turned camera) are seen at
  those pixels, at their depth, with their normal, and unproject back onto themselves.
- The masks through such a camera are the float64 brute force's (tests/exact.py).
"""

from __future__ import annotations

import numpy as np
import pytest
from builders import (
    SCENES,
    camera_from_matrices,
    cards_scene,
    check_seen,
    mixed_scene,
    off_centre,
    pixel_targets,
)

from exact import check_exact

import raytrace
from shadowvol.cli.raytrace import main as raytrace_main
from shadowvol.scene import Camera, DirectionalLight, PointLight
from shadowvol.scenefile import load_scene, save_scene

SIZE = dict(width=96, height=72)


def _scenes():
    return {"cage": load_scene(SCENES / "cage.toml").replace(**SIZE),
            "stack": load_scene(SCENES / "stack.toml").replace(**SIZE),
            "cards off-centre": off_centre(cards_scene(**SIZE))}


@pytest.mark.parametrize("name", sorted(_scenes()))
def test_written_matrices_read_back_give_the_same_file(tmp_path, name):
    scene = _scenes()[name]
    first = tmp_path / "first.toml"
    save_scene(scene, first)
    assert raytrace_main(["masks", str(first), "-o", str(tmp_path / "a.npz"), "--no-png",
                          "--outputs", "all"]) == 0
    a = dict(np.load(tmp_path / "a.npz"))
    camera = camera_from_matrices(a["K"], a["camera_to_world"], scene.camera.near)
    second = tmp_path / "second.json"
    save_scene(load_scene(first).replace(camera=camera), second)
    assert raytrace_main(["masks", str(second), "-o", str(tmp_path / "b.npz"), "--no-png",
                          "--outputs", "all"]) == 0
    b = dict(np.load(tmp_path / "b.npz"))
    assert sorted(a) == sorted(b)
    for key in a:
        assert a[key].dtype == b[key].dtype and np.array_equal(a[key], b[key], equal_nan=True), key
    assert a["lit"].any() and (a["coverage"][None] & ~a["lit"]).any()   # shadows to compare
    if scene.camera.matrix_form:   # written back exactly as given
        assert np.array_equal(a["camera_to_world"], scene.camera.camera_to_world)
        assert a["K"].tolist() == [[scene.camera.fx, 0, scene.camera.cx],
                                   [0, scene.camera.fy, scene.camera.cy], [0, 0, 1]]


@pytest.mark.parametrize("seed", range(6))
def test_points_projected_with_K_are_seen_at_their_pixel(seed):
    scene, centres, pixels, K = pixel_targets(seed)
    truth = raytrace.ground_truth(scene, outputs=("depth", "normal", "object_id"))
    np.testing.assert_array_equal(truth.calibration.K, K)
    np.testing.assert_array_equal(truth.calibration.camera_to_world,
                                  scene.camera.camera_to_world)
    check_seen(K, truth.calibration.camera_to_world, centres, pixels, truth.object_id,
               truth.depth, truth.normal)


@pytest.mark.parametrize("seed", range(8))
def test_random_look_at_cameras_read_back_bit_for_bit(seed):
    """Random eyes, targets, ups (not perpendicular to the view), fields of view and image
    shapes: the look-at camera and its written K and camera_to_world give the same ground
    truth, every output, bit for bit."""
    rng = np.random.default_rng(seed)
    base = mixed_scene(seed)
    camera = Camera(eye=rng.uniform(-6, 6, 3) + [0, 6, 0], target=rng.uniform(-2, 2, 3),
                    up=rng.normal(size=3) + [0, 2, 0], fov_y=rng.uniform(20, 100),
                    near=rng.uniform(0.01, 0.5))
    scene = base.replace(camera=camera, width=int(rng.integers(30, 90)),
                         height=int(rng.integers(30, 90)))
    a = raytrace.ground_truth(scene)
    cal = a.calibration
    b = raytrace.ground_truth(scene.replace(
        camera=camera_from_matrices(cal.K, cal.camera_to_world, camera.near)))
    for name, value in {**a.arrays(), "lit": a.lit, "coverage": a.coverage}.items():
        other = {**b.arrays(), "lit": b.lit, "coverage": b.coverage}[name]
        assert value.dtype == other.dtype and np.array_equal(value, other, equal_nan=True), name


@pytest.mark.parametrize("light", ["directional", "point"])
def test_off_centre_masks_are_the_float64_brute_forces(request, light):
    """Non-square pixels and an off-centre principal point: Embree's masks against the float64
    brute force of tests/exact.py (every triangle tried per pixel ray), under its budget."""
    lamp = (DirectionalLight([0.3, -1.0, -0.2]) if light == "directional"
            else PointLight([0.4, 3.0, 0.6]))
    check_exact(request, off_centre(cards_scene(96, 72, lamp)))
