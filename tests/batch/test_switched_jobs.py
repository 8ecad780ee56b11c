"""A batch job over a scene file with shadow switches (an object that casts none, one that
receives none, a light override that casts none) writes the switched masks and arrays, from
both renderers: the arrays the API gives for the switched scene, which are not the unswitched
scene's."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from builders import overlapping_shadows, switched

import raytrace
from shadowvol import batch
from shadowvol.frame import decode_casters
from shadowvol.io import load_mask_arrays
from shadowvol.raster.renderer import Renderer
from shadowvol.scenefile import light_from_dict, load_scene, save_scene

ARRAYS = ["casters", "facing_count", "object_id"]
LIGHTS = [{"type": "point", "position": [1.5, 4.0, 1.5]},
          {"type": "directional", "direction": [-0.3, -1.0, -0.2], "shadows": False}]


@pytest.mark.gl
def test_a_batch_job_writes_the_switched_masks(tmp_path):
    base = overlapping_shadows(width=48, height=36)
    path = tmp_path / "switched.toml"
    save_scene(switched(base, cast=[3], receive=[1]), path)   # the card, the post
    cam = {"eye": base.camera.eye.tolist(), "target": base.camera.target.tolist(),
           "fov_y": base.camera.fov_y}
    jobs = [{"name": name, "scene": str(path), "renderer": name, "cameras": [cam],
             "lights": LIGHTS, "outputs": ["masks", *ARRAYS]}
            for name in ("shadowvol", "raytrace")]
    assert batch.run(jobs, tmp_path / "out", progress=False).status == 0

    lights = tuple(light_from_dict(lt) for lt in LIGHTS)
    assert [lt.shadows for lt in lights] == [True, False]
    scene = load_scene(path).replace(lights=lights)
    assert [(o.cast_shadows, o.receive_shadows) for o in scene.objects] == [
        (True, True), (True, False), (True, True), (False, True)]
    truth = raytrace.ground_truth(scene, outputs=ARRAYS)
    with Renderer(scene) as r:
        raster = r.render(outputs=("lit", "coverage", *ARRAYS))
    plain = raytrace.ground_truth(base.replace(lights=(
        lights[0], dataclasses.replace(lights[1], shadows=True))), outputs=ARRAYS)
    for name, frame in (("shadowvol", raster), ("raytrace", truth)):
        folder = tmp_path / "out" / name
        masks = load_mask_arrays(folder / "000000.masks.npz")
        arrays = {a: np.load(folder / f"000000.{a}.npy") for a in ARRAYS}
        np.testing.assert_array_equal(masks["lit"], frame.lit)
        for a in ARRAYS:
            np.testing.assert_array_equal(arrays[a], getattr(frame, a))
        bits = decode_casters(arrays["casters"], len(scene.objects))
        assert not bits[..., 3].any()                              # the card casts nothing
        assert not bits[:, arrays["object_id"] == 2].any()         # nothing on the post
        assert not bits[1].any()                                   # the sun casts nothing
        np.testing.assert_array_equal(masks["lit"][1], arrays["facing_count"][1] > 0)
        assert (masks["lit"] != plain.lit).any(axis=(1, 2)).all()  # both lights switched
