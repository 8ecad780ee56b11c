"""The rasterizer ignores the distributed ray tracer's keys (camera aperture and focus_distance,
material roughness): it stays a pinhole, mirror-less renderer and draws the same frame."""

from __future__ import annotations

import dataclasses

import numpy as np
from builders import SCENES

from shadowvol.raster.renderer import Renderer
from shadowvol.scenefile import load_scene


def test_lens_and_roughness_change_no_pixel_of_the_raster(ctx):
    plain = load_scene(SCENES / "whitted.toml").replace(width=64, height=48)
    camera = dataclasses.replace(plain.camera, aperture=0.2, focus_distance=3.0)
    objects = [dataclasses.replace(o, material=dataclasses.replace(o.material, roughness=0.5))
               for o in plain.objects]
    keyed = plain.replace(camera=camera, objects=objects)
    with Renderer(plain, ctx) as r:
        a = r.render()
    with Renderer(keyed, ctx) as r:
        b = r.render()
    assert np.array_equal(a.image, b.image)
    assert np.array_equal(a.lit, b.lit) and np.array_equal(a.coverage, b.coverage)
