"""A batch job over a scene file whose mesh is a textured glTF writes the textured images, from
both renderers: the images the API gives for the loaded scene (the batch loads scene files the
same way), which are not the untextured scene's."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from builders import GL_LINEAR, GL_REPEAT, textured_glb, textured_scene_file
from PIL import Image

import raytrace
from shadowvol import batch
from shadowvol.io import encode_srgb
from shadowvol.raster.renderer import Renderer
from shadowvol.scenefile import load_scene


@pytest.mark.gl
def test_a_batch_job_writes_the_textured_images(tmp_path):
    texels = np.random.default_rng(4).integers(0, 256, (8, 8, 3)).astype(np.uint8)
    textured_glb(tmp_path / "quad.glb", texels, wrap=GL_REPEAT, filt=GL_LINEAR)
    path = textured_scene_file(tmp_path, "quad.glb", width=48, height=40)
    cam = {"eye": [0.3, 2.2, 1.9], "target": [0.0, 0.0, 0.0], "fov_y": 50.0}
    jobs = [{"name": name, "scene": str(path), "renderer": name, "cameras": [cam],
             "outputs": ["image"], **({"max_depth": 0} if name == "raytrace" else {})}
            for name in ("shadowvol", "raytrace")]
    assert batch.run(jobs, tmp_path / "out", progress=False).status == 0
    scene = load_scene(path)
    with Renderer(scene) as r:
        raster = encode_srgb(r.render().image)
    traced = encode_srgb(raytrace.render(scene, max_depth=0, progress=False))
    quad = scene.objects[0]
    plain = scene.replace(objects=(dataclasses.replace(
        quad, uv=None, material=dataclasses.replace(quad.material, texture=None)),))
    flat = encode_srgb(raytrace.render(plain, max_depth=0, progress=False))
    for name, want in (("shadowvol", raster), ("raytrace", traced)):
        written = sorted((tmp_path / "out" / name).glob("*.png"))
        assert len(written) == 1, written
        got = np.asarray(Image.open(written[0]).convert("RGB"))
        np.testing.assert_array_equal(got, want)
        assert (np.abs(got.astype(int) - flat).max(axis=2) > 8).mean() > 0.2
