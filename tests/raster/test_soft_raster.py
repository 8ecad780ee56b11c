"""The rasterizer's soft shadows against the ray tracer's, per pixel and per sample.

Each sample of an area light is counted with the same exact stencil test as a point light, so
raster and ray tracer `lit_count` must be EQUAL at every pixel that is not on an edge (one pixel
either side, `maskdiff.edge_pixels`) of some sample's hard mask or of the coverage: there one
sample may fall either way, as for any hard mask.  Checked on every scene in scenes/ with its
lights made area lights, and on built cases; N = 1 is the point light.
"""

from __future__ import annotations

import numpy as np
import pytest
from builders import ROOT, check_counts, square_light, square_over_floor

import raytrace
from shadowvol.compare.maskdiff import count_edges
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import AreaLight, DirectionalLight, PointLight, SpotLight
from shadowvol.scenefile import load_scene

SCENE_FILES = sorted(p for p in (ROOT / "scenes").iterdir() if p.suffix in (".toml", ".json"))
RUNS = [("auto", "cpu"), ("zfail", "gpu")]


def _as_area(light, how: str):
    """The scene's light made an area light around its position (directional lights stay)."""
    if isinstance(light, (DirectionalLight, AreaLight)):
        return light
    common = dict(center=light.position, color=light.color, intensity=light.intensity,
                  samples=4)
    if isinstance(light, SpotLight):
        return AreaLight("disk", normal=light.direction, radius=0.3, **common)
    if how == "sphere":
        return AreaLight("sphere", radius=0.1, pattern="halton", **common)
    return AreaLight("rect", normal=[0.0, -1.0, 0.0], size=[0.6, 0.4], seed=1, **common)


def _variants():
    """(scene file, how) pairs: both substitutions where a scene has a point light to make an
    area light, the scene as it is where it has area lights already."""
    for path in SCENE_FILES:
        lights = load_scene(path).lights
        if any(isinstance(lt, PointLight) for lt in lights):
            yield from ((path, how) for how in ("sphere", "rect"))
        else:
            yield path, "as is"


@pytest.mark.parametrize("path, how", list(_variants()), ids=lambda v: getattr(v, "name", v))
def test_scene_files_with_area_lights(ctx, path, how):
    scene = load_scene(path).replace(width=96, height=72)
    scene = scene.replace(lights=tuple(_as_area(lt, how) for lt in scene.lights))
    ref = raytrace.soft_masks(scene)
    with Renderer(scene, ctx) as r:
        for run in RUNS:
            check_counts(scene, r.render(*run), ref)


@pytest.mark.parametrize("light", [
    square_light(16),
    square_light(16, pattern="halton", seed=3),
    AreaLight("disk", [0.0, 2.5, 0.0], normal=[0.3, -1.0, 0.1], radius=0.7, samples=16),
    AreaLight("sphere", [0.0, 2.5, 0.0], radius=0.6, samples=16),
    AreaLight("sphere", [0.2, 1.0, 0.0], radius=0.4, samples=16),  # through the occluder
], ids=["rect", "rect-halton", "disk", "sphere", "sphere-cut"])
def test_built_cases(ctx, light):
    scene = square_over_floor(light, size=96)
    ref = raytrace.soft_masks(scene)
    assert ref.penumbra.any()
    with Renderer(scene, ctx) as r:
        for run in RUNS:
            rows = check_counts(scene, r.render(*run), ref)
        res = r.render()
    assert rows[0]["differ"] <= 2, rows  # this scene has almost nothing to disagree about
    assert res.samples.tolist() == [light.samples] and res.visibility.dtype == np.float32
    assert res.penumbra.any() and not (res.penumbra & res.lit).any()
    np.testing.assert_allclose(res.visibility[0], ref.visibility[0], atol=1.0 / 16 + 1e-7)
    # facing and umbra as the ray tracer has them, off the samples' edges
    with Renderer(scene, ctx) as r:
        facing = r.facing()
    umbra = facing & (res.lit_count == 0)
    near = count_edges(facing[0].astype(np.uint8)) | count_edges(ref.facing[0].astype(np.uint8))
    assert not ((facing[0] != ref.facing[0]) & ~near).any()
    assert (umbra != ref.umbra).sum() <= 2
    assert umbra.any() or light.shape == "sphere"  # (a sphere light may leave none on screen)


def test_one_sample_is_the_point_light(ctx):
    light = square_light(1, seed=4)
    area, point = (square_over_floor(lt, size=64) for lt in (light, PointLight(light.positions[0])))
    with Renderer(area, ctx) as r:
        soft = r.render()
    with Renderer(point, ctx) as r:
        hard = r.render()
    np.testing.assert_array_equal(soft.lit, hard.lit)
    np.testing.assert_array_equal(soft.lit_count[0], hard.lit[0])
    np.testing.assert_array_equal(hard.lit_count, hard.lit)  # a hard light counts to 1
    np.testing.assert_array_equal(soft.lit, raytrace.shadow_masks(area)[0])


def test_image_is_the_ray_tracers_direct_light(ctx):
    """The raster's soft shadow shades like Whitted's direct light (max_depth 0): the same
    samples, shares and cosines at the light."""
    scene = square_over_floor(square_light(16, intensity=1.5), size=96)
    with Renderer(scene, ctx) as r:
        image = r.render().image
    ray = raytrace.render(scene, max_depth=0, progress=False)
    error = np.abs(image - ray).max(axis=2)
    assert (error > 1e-4).sum() <= 0.002 * error.size, int((error > 1e-4).sum())
    assert np.unique(np.round(image[..., 0], 3)).size > 50  # many grey levels: soft


def test_stencil_counts_refused_for_area_lights(ctx):
    with Renderer(square_over_floor(square_light(4), size=16), ctx) as r:
        with pytest.raises(ValueError, match="area lights"):
            r.render(stencil=True)


def test_a_sample_whose_count_wraps_raises(ctx):
    """256 sheets between an area light and the floor: each sample's count under the stack is
    256, which the 8-bit stencil reads as 0; the overflow check runs per sample and raises
    instead of calling those pixels lit."""
    from shadowvol.primitives import mesh, plane
    from shadowvol.raster.overflow import detect
    from shadowvol.scene import Camera, Scene

    z = np.linspace(1.0, 2.0, 256)
    corners = np.array([[-0.5, 0, -0.5], [0.5, 0, -0.5], [0.5, 0, 0.5], [-0.5, 0, 0.5]])
    v = corners[None] + np.stack([np.zeros_like(z), z, np.zeros_like(z)], 1)[:, None]
    f = np.array([[0, 1, 2], [0, 2, 3]])[None] + 4 * np.arange(256)[:, None, None]
    light = AreaLight("rect", [0.1, 4.0, 0.05], normal=[0, -1, 0], size=[0.2, 0.2], samples=4)
    scene = Scene(Camera(eye=[0, 0.8, 3.0], target=[0, 0, 0], fov_y=60),
                  [plane("floor", size=[6, 6]),
                   mesh("sheets", v.reshape(-1, 3), f.reshape(-1, 3))],
                  [light], width=64, height=48)
    ref = raytrace.soft_masks(scene)
    assert ref.umbra.sum() > 100
    with Renderer(scene, ctx) as r:
        with pytest.raises(detect.StencilOverflowError, match="light 0"):
            r.render()
        r.check_overflow = False
        wrapped = r.render()
    assert (wrapped.lit_count[0][ref.umbra[0]] > 0).any()  # what the check keeps out


def test_render_command_writes_the_samples(ctx, tmp_path):
    from shadowvol.cli.main import main as shadowvol_main
    from shadowvol.scenefile import save_scene

    scene = square_over_floor(square_light(9, pattern="halton"), size=24)
    save_scene(scene, tmp_path / "s.json")
    assert shadowvol_main(["render", str(tmp_path / "s.json"), "-o", str(tmp_path / "s.png"),
                     "--masks", str(tmp_path / "m.npz")]) == 0
    with np.load(tmp_path / "m.npz", allow_pickle=False) as data:
        np.testing.assert_array_equal(data["light_samples_0"], scene.lights[0].positions)
        with Renderer(scene, ctx) as r:
            np.testing.assert_array_equal(data["lit"], r.render().lit)
