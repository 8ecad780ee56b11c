"""The rasterizer's intrinsic layers (docs/CONVENTIONS.md, "Intrinsic layers"): both identities
to the float32 bound of tests/layers.py, `shadow_free` bit-identical to the frame with every
light's shadows off, hard lights' lit · direct, the albedo of a textured quad against its texels,
and every layer against the ray tracer's within the raster-vs-ray image budget (IMAGE_TOL on
all but IMAGE_BUDGET of the channels, as the images themselves)."""

from __future__ import annotations

import numpy as np
import pytest
from builders import (
    IMAGE_BUDGET,
    IMAGE_TOL,
    mixed_scene,
    overlapping_shadows,
    square_light,
    square_over_floor,
    switched,
)
from layers import check_albedo, check_identities, check_shadowed, textured_quad

from raytrace.outlook.layers import layers
from shadowvol.frame import LAYERS
from shadowvol.primitives import box
from shadowvol.raster.renderer import Renderer, render

pytestmark = pytest.mark.gl



def boxed() -> "Scene":
    """overlapping_shadows with its ball a box: the ray tracer intersects a sphere
    analytically and the rasterizer its triangles, so the images' agreement holds for meshes
    (the raster-vs-ray image tests' scenes have no spheres either)."""
    scene = overlapping_shadows(60, 45)
    objects = list(scene.objects)
    objects[2] = box("ball", [0.7, 0.45, 0.5], [0.7, 0.9, 0.7])
    return scene.replace(objects=objects)


SCENES = {"overlapping": boxed, "soft": lambda: square_over_floor(square_light(16), size=64),
          "mixed": lambda: mixed_scene(2)}
# the scenes whose images agree with the ray tracer's (mixed_scene has spheres)
AGREE = ("overlapping", "soft")


def within_budget(raster: np.ndarray, ray: np.ndarray, label: str) -> None:
    """test_soft_raster.test_image_is_the_ray_tracers_direct_light's rule: a pixel's largest
    channel error over IMAGE_TOL in at most IMAGE_BUDGET of the pixels."""
    error = np.abs(raster.astype(np.float64) - ray.astype(np.float64)).max(axis=-1)
    bad = int((error > IMAGE_TOL).sum())
    assert bad <= IMAGE_BUDGET * error.size, \
        f"{label}: {bad} pixels differ by more than {IMAGE_TOL} (budget " \
        f"{IMAGE_BUDGET * error.size:.0f}, worst {error.max()})"


@pytest.mark.parametrize("name", list(SCENES))
def test_identities_and_the_ray_tracer(ctx, name):
    scene = SCENES[name]()
    L = len(scene.lights)
    with Renderer(scene, ctx) as r:
        got = r.render(outputs=("image", "lit") + LAYERS)
        free = r.render(lights=switched(scene, lights=range(L)).lights,
                        outputs=("image",)).image
    assert all(getattr(got, n).dtype == np.float32 for n in LAYERS)
    assert got.direct.shape == (L, scene.height, scene.width, 3)
    # the shadow-free twin is the same render: bit for bit
    assert np.array_equal(got.shadow_free, free)
    lay = {n: getattr(got, n) for n in LAYERS}
    check_identities(lay, got.image, free)
    check_shadowed(scene, lay)
    assert (got.direct_shadowed < got.direct).any()
    # a hard light's direct_shadowed is lit · direct
    for i, light in enumerate(scene.lights):
        if got.samples[i] == 1:
            assert np.array_equal(got.direct_shadowed[i],
                                  got.direct[i] * got.lit[i][..., None])
    if name not in AGREE:
        return
    ray = layers(scene)
    for n in LAYERS:
        within_budget(lay[n], ray[n], n)


def test_albedo_is_the_texel_under_the_pixel(ctx, tmp_path):
    scene, tex = textured_quad(tmp_path)
    albedo = render(scene, ctx=ctx, outputs=("albedo",)).albedo
    # the shading pass's float32 texel decode times kd: IMAGE_TOL, the textures' own test's
    assert check_albedo(scene, tex, albedo, atol=IMAGE_TOL) > 100


def test_only_a_layer(ctx):
    scene = overlapping_shadows(30, 20)
    with Renderer(scene, ctx) as r:
        got = r.render(outputs=("ambient",))
    assert got.image is None and got.lit is None and got.ambient.shape == (20, 30, 3)
