"""Cameras given by matrices in the rasterizer (docs/CONVENTIONS.md, "Camera matrices").

- The K and camera_to_world `shadowvol render --masks` writes, read back as its camera (a
  scene file's `fx`, `fy`, `cx`, `cy`, `camera_to_world`), give the same mask file and image
  again bit for bit.
- Non-square pixels and an off-centre principal point: the raster masks equal the ray tracer's
  under the masks' budget (conftest.assert_masks_match), for every method and silhouette path.
- Independent of the renderers: squares placed at known pixels by K and camera_to_world in
  float64 are seen by the rasterizer at those pixels, at their depth, with their normal.
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

import raytrace
from shadowvol.cli.main import main as shadowvol_main
from shadowvol.raster.renderer import Renderer
from shadowvol.raster.result import OUTPUTS
from shadowvol.scene import Camera
from shadowvol.scenefile import load_scene, save_scene

SIZE = dict(width=96, height=72)
RUNS = [("auto", "cpu"), ("auto", "gpu"), ("zfail", "cpu"), ("zfail", "gpu")]


def _render(path, out) -> dict:
    assert shadowvol_main(["render", str(path), "-o", str(out / "image.png"), "--masks",
                           str(out / "masks.npz"), "--outputs", "all"]) == 0
    return {**dict(np.load(out / "masks.npz")), "png": (out / "image.png").read_bytes()}


@pytest.mark.parametrize("name", ["cage", "stack", "cards off-centre"])
def test_written_matrices_read_back_give_the_same_file(tmp_path, name):
    scene = (off_centre(cards_scene(**SIZE)) if name == "cards off-centre"
             else load_scene(SCENES / f"{name}.toml").replace(**SIZE))
    first = tmp_path / "first.toml"
    save_scene(scene, first)
    (tmp_path / "a").mkdir(), (tmp_path / "b").mkdir()
    a = _render(first, tmp_path / "a")
    camera = camera_from_matrices(a["K"], a["camera_to_world"], scene.camera.near)
    second = tmp_path / "second.toml"
    save_scene(load_scene(first).replace(camera=camera), second)
    b = _render(second, tmp_path / "b")
    assert sorted(a) == sorted(b)
    for key in a:
        if key != "png":
            assert a[key].dtype == b[key].dtype, key
        assert np.array_equal(a[key], b[key], equal_nan=True) if key != "png" \
            else a[key] == b[key], key
    assert a["lit"].any() and (a["coverage"][None] & ~a["lit"]).any()


@pytest.mark.parametrize("name", ["cage", "stack", "planar", "mixed 3", "cards"])
def test_off_centre_masks_equal_the_ray_tracers(ctx, assert_masks_match, name):
    base = (mixed_scene(3) if name == "mixed 3" else cards_scene(**SIZE) if name == "cards"
            else load_scene(SCENES / f"{name}.toml").replace(width=128, height=96))
    scene = off_centre(base)
    assert scene.camera.fx != scene.camera.fy
    ref_lit, ref_cov = raytrace.shadow_masks(scene)
    with Renderer(scene, ctx) as r:
        results = {run: r.render(*run) for run in RUNS}
    for (method, silhouettes), res in results.items():
        assert_masks_match(res, ref_lit, ref_cov, f"{method}-{silhouettes}")
        np.testing.assert_array_equal(res.calibration.camera_to_world,
                                      scene.camera.camera_to_world)
    # the view really moved: the look-at camera's masks differ
    assert (raytrace.shadow_masks(base)[0] != ref_lit).sum() > 0.01 * ref_lit.size


@pytest.mark.parametrize("seed", range(6))
def test_points_projected_with_K_are_seen_at_their_pixel(ctx, seed):
    scene, centres, pixels, K = pixel_targets(seed)
    with Renderer(scene, ctx) as r:
        res = r.render(outputs=("coverage", "depth", "normal", "object_id"))
    np.testing.assert_array_equal(res.calibration.K, K)
    check_seen(K, res.calibration.camera_to_world, centres, pixels, res.object_id, res.depth,
               res.normal)


@pytest.mark.parametrize("seed", range(4))
def test_random_look_at_cameras_read_back_bit_for_bit(ctx, seed):
    """Random look-at cameras and image shapes: the camera and its written K and
    camera_to_world give the same frame, every output (the stencil counts and the z-fail
    choices too), bit for bit, with both methods and both silhouette paths."""
    rng = np.random.default_rng(seed)
    camera = Camera(eye=rng.uniform(-6, 6, 3) + [0, 6, 0], target=rng.uniform(-2, 2, 3),
                    up=rng.normal(size=3) + [0, 2, 0], fov_y=rng.uniform(20, 100),
                    near=rng.uniform(0.01, 0.5))
    scene = mixed_scene(seed).replace(camera=camera, width=int(rng.integers(30, 90)),
                                      height=int(rng.integers(30, 90)))
    with Renderer(scene, ctx) as r:
        for run in RUNS:
            a = r.render(*run, stencil=True, outputs=OUTPUTS)
            cal = a.calibration
            b = r.render(*run, stencil=True, outputs=OUTPUTS,
                         camera=camera_from_matrices(cal.K, cal.camera_to_world, camera.near))
            for name in (*OUTPUTS, "stencil", "zfail", "lit_count", "samples"):
                x, y = getattr(a, name), getattr(b, name)
                assert x.dtype == y.dtype and np.array_equal(x, y, equal_nan=True), (run, name)
            for x, y in zip(cal, b.calibration):
                assert np.array_equal(x, y)
