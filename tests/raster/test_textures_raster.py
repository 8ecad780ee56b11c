"""Textures, MTL colours and vertex colours in the rasterizer (docs/CONVENTIONS.md,
"Textures"): a textured glTF written here renders texel for texel as Whitted renders it
(nearest and bilinear, repeat, clamp and mirror), within the raster-vs-ray image budget; a few
pixels against the rule computed independently in float64; the texture reaches the shading
pass from the G-buffer's UVs in one frame with untextured objects beside it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from builders import (
    GL_CLAMP,
    GL_LINEAR,
    GL_MIRROR,
    GL_NEAREST,
    GL_REPEAT,
    IMAGE_BUDGET,
    IMAGE_TOL,
    textured_glb,
    textured_scene_file,
)
from layers import quad_texels, textured_quad

import raytrace
from shadowvol.io import save_png
from shadowvol.primitives import box
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import Material, PointLight
from shadowvol.scenefile import load_scene

pytestmark = pytest.mark.gl

SAMPLERS = [(GL_NEAREST, GL_REPEAT), (GL_LINEAR, GL_REPEAT), (GL_NEAREST, GL_CLAMP),
            (GL_LINEAR, GL_CLAMP), (GL_NEAREST, GL_MIRROR), (GL_LINEAR, GL_MIRROR)]


def texels(seed: int = 0, size=(8, 8)) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 256, (*size, 3)).astype(np.uint8)


def check_images(raster, ray, out_dir, label: str) -> None:
    """The raster-vs-ray image budget; on failure both images and their difference are
    written under `out_dir`."""
    error = np.abs(raster - ray).max(axis=2)
    bad = int((error > IMAGE_TOL).sum())
    if bad > IMAGE_BUDGET * error.size:
        save_png(out_dir / f"{label}-raster.png", raster)
        save_png(out_dir / f"{label}-ray.png", ray)
        save_png(out_dir / f"{label}-diff.png", np.repeat((error > IMAGE_TOL)[..., None], 3, 2)
                 .astype(np.float64))
        pytest.fail(f"{label}: {bad} pixels differ by more than {IMAGE_TOL} (budget "
                    f"{IMAGE_BUDGET * error.size:.0f}); images in {out_dir}")


@pytest.mark.parametrize("filt,wrap", SAMPLERS)
def test_textured_gltf_renders_as_the_ray_tracer_sees_it(ctx, tmp_path, filt, wrap):
    textured_glb(tmp_path / "quad.glb", texels(), wrap=wrap, filt=filt,
                 factor=(0.9, 0.7, 0.8, 1.0))
    scene = load_scene(textured_scene_file(tmp_path, "quad.glb"))
    with Renderer(scene, ctx) as r:
        raster = r.render().image
    ray = raytrace.render(scene, max_depth=0, progress=False)
    check_images(raster, ray, tmp_path, f"{filt}-{wrap}")
    covered = (ray != scene.background).any(axis=2)
    assert covered.sum() > 2000
    # the texture is there, in both: dozens of colours, none of them the untextured one
    assert len(np.unique(raster[covered].round(4), axis=0)) > 40
    plain = scene.replace(objects=(untextured(scene.objects[0]),))
    with Renderer(plain, ctx) as r:
        flat = r.render().image
    assert (np.abs(flat - raster)[covered] > 0.01).mean() > 0.5


def untextured(obj):
    return dataclasses.replace(obj, material=dataclasses.replace(obj.material, texture=None),
                               uv=None)


def test_a_pixel_is_the_texel_under_its_uv(ctx, tmp_path):
    """Nearest, repeat, a camera straight down on the quad: pixel centres map to UVs by an
    affine map, so the texel under a pixel is known in float64 without any renderer."""
    scene, tex = textured_quad(tmp_path)
    with Renderer(scene, ctx) as r:
        image = r.render().image
    cam, m, light = scene.camera, scene.objects[0].material, scene.lights[0]
    checked = 0
    for x, y, p, base in quad_texels(scene, tex):
        l = (light.position - p) / np.linalg.norm(light.position - p)
        view = (cam.eye - p) / np.linalg.norm(cam.eye - p)
        r = 2 * l[1] * np.array([0, 1.0, 0]) - l
        want = m.ambient * base * scene.ambient + (
            m.diffuse * base * l[1] + m.specular * max(r.dot(view), 0) ** m.shininess
        ) * light.radiance
        np.testing.assert_allclose(image[y, x], want, rtol=0, atol=IMAGE_TOL,
                                   err_msg=f"pixel ({x}, {y})")
        checked += 1
    assert checked > 100


def test_textured_and_plain_objects_in_one_frame(ctx, tmp_path, assert_masks_match):
    """A textured quad, a box with vertex colours and an untextured box, and a shadow: one
    frame, the ray tracer's image within the budget, and the masks unchanged by the surface
    attributes."""
    textured_glb(tmp_path / "quad.glb", texels(5, (16, 4)), wrap=GL_CLAMP, filt=GL_LINEAR)
    scene = load_scene(textured_scene_file(tmp_path, "quad.glb"))
    plain = box("plain", center=[-0.4, 0.2, 0.0], size=[0.3, 0.4, 0.3])
    tinted = box("tinted", center=[0.4, 0.15, 0.2], size=[0.3, 0.3, 0.3],
                 material=Material(diffuse=[0.6, 0.6, 0.6]))
    colours = np.random.default_rng(2).random((len(tinted.vertices), 3))
    tinted = dataclasses.replace(tinted, colors=colours)
    scene = scene.replace(objects=scene.objects + (plain, tinted),
                          lights=(PointLight([1.5, 1.2, 1.0]),))
    with Renderer(scene, ctx) as r:
        res = r.render()
    ray = raytrace.render(scene, max_depth=0, progress=False)
    check_images(res.image, ray, tmp_path, "mixed")
    lit, cov = raytrace.shadow_masks(scene)
    assert_masks_match(res, lit, cov)
    assert (~lit[0] & cov).sum() > 100   # the boxes' shadows are in the frame


def test_a_huge_textured_ground_cut_to_the_guard_band(ctx, tmp_path):
    """A ground 2e5 wide, seen from 1 above: its triangles are cut to the view's guard band
    (`SceneGeometry.set_view`), and the pieces' UVs and colours, interpolated in float64 at
    their corners, give the image the ray tracer gives for the whole triangles."""
    from shadowvol.primitives import mesh
    from shadowvol.scene import Camera, Scene
    from shadowvol.textures import Texture

    half = 1e5
    v = np.array([[-half, 0, -half], [half, 0, -half], [half, 0, half], [-half, 0, half]])
    uv = np.array([[0.0, 0.0], [8.0, 0.0], [8.0, 8.0], [0.0, 8.0]])
    colours = np.array([[1.0, 0.2, 0.2], [0.2, 1.0, 0.2], [0.2, 0.2, 1.0], [1.0, 1.0, 1.0]])
    tex = Texture(texels(7), "repeat", "mirror", "linear")
    ground = mesh("ground", v, [[0, 1, 2], [0, 2, 3]], Material(texture=tex), uv=uv,
                  colors=colours)
    scene = Scene(Camera(eye=[3.0, 1.0, 5.0], target=[-40.0, 0.0, -200.0], fov_y=60),
                  [ground], [PointLight([0.0, 50.0, 0.0])], width=96, height=64)
    with Renderer(scene, ctx) as r:
        raster = r.render().image
        assert len(r.geometry.holes) == 2    # both triangles were cut
    ray = raytrace.render(scene, max_depth=0, progress=False)
    check_images(raster, ray, tmp_path, "huge")
    covered = (ray != scene.background).any(axis=2)
    assert len(np.unique(raster[covered].round(4), axis=0)) > 100


def test_textures_change_the_image_and_nothing_else(ctx, tmp_path):
    """Every ground-truth output of a textured scene is the untextured scene's, bit for bit;
    the 8-bit image the shading pass encodes itself is the float image's, within one code.
    (The intrinsic layers are shading, like the image: the texture is in them, and its
    albedo is checked texel by texel in tests/raster/test_layers_raster.py.)"""
    from shadowvol.frame import LAYERS
    from shadowvol.io import encode_srgb
    from shadowvol.raster.result import OUTPUTS

    textured_glb(tmp_path / "quad.glb", texels(8), wrap=GL_MIRROR, filt=GL_LINEAR)
    scene = load_scene(textured_scene_file(tmp_path, "quad.glb"))
    plain = scene.replace(objects=(untextured(scene.objects[0]),))
    truth = tuple(o for o in OUTPUTS if o not in ("image", "image_srgb", "stencil") + LAYERS)
    with Renderer(scene, ctx) as r:
        got = r.render(outputs=truth + ("image_srgb",))
        image = r.render().image
    with Renderer(plain, ctx) as r:
        want = r.render(outputs=truth + ("image_srgb",))
    for name in truth:
        np.testing.assert_array_equal(getattr(got, name), getattr(want, name), err_msg=name)
    assert (got.image_srgb != want.image_srgb).any()
    assert np.abs(got.image_srgb.astype(int) - encode_srgb(image)).max() <= 1
