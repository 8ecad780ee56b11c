"""The mask pass: a frame that asks for the masks alone (`outputs` within lit and coverage, one
page of hard lights) writes its lit bits in the geometry pass and clears each light's bit where
its stencil count is not 0 (`passes.mask_pass`, `passes.clear_shadowed`), with no G-buffer and
no shading pass.  Its masks must be the deferred frame's bit for bit, for every light kind,
method, silhouette path and culling, and with many lights in one framebuffer; a frame of more
lights than a page, or asking for anything else, takes the deferred passes.

Up to 6 hard lights whose counts fit beside the bits keep the bits in the stencil instead of a
colour target (`stencil.mask_layout`, `Renderer._masks_fit_stencil`): the same masks again,
with either layout, and the colour target wherever a count could reach the stencil's smaller
modulus.

The random-scene and large-world properties check the same equality on their scenes
(test_random_scenes.check_scene, test_large_worlds.raster_masks), and the ray tracer's masks
are compared with the deferred frame there: this file makes the mask pass answer to both.
"""

from __future__ import annotations

import numpy as np
import pytest
from builders import mixed_scene

import raytrace
from shadowvol.primitives import box, plane, sphere
from shadowvol.raster import passes, stencil
from shadowvol.raster.renderer import Renderer
from shadowvol.raster.target import LIGHTS_PER_PAGE
from shadowvol.scene import (AreaLight, Camera, DirectionalLight, Material, Object, PointLight,
                             Scene, SpotLight)

MASKS = ("lit", "coverage")


def assert_same_masks(masks, full, label: str = "") -> None:
    np.testing.assert_array_equal(masks.lit, full.lit, err_msg=label)
    np.testing.assert_array_equal(masks.lit_count, full.lit_count, err_msg=label)
    np.testing.assert_array_equal(masks.coverage, full.coverage, err_msg=label)
    np.testing.assert_array_equal(masks.zfail, full.zfail, err_msg=label)


class Taken(list):
    """The names of the frame passes each render ran ("mask" or "shade"); `in_stencil`: for
    each mask pass, whether it kept the bits in the stencil."""

    def __init__(self):
        super().__init__()
        self.in_stencil: list[bool] = []


@pytest.fixture
def passes_taken(monkeypatch):
    """The frame passes each render runs (`Taken`), for asserting which path a frame took."""
    taken = Taken()
    for name, label in (("mask_pass", "mask"), ("shade", "shade")):
        original = getattr(passes, name)

        def spy(*args, _original=original, _label=label, **kwargs):
            taken.append(_label)
            if _label == "mask":
                taken.in_stencil.append(bool(kwargs.get("in_stencil", False)))
            return _original(*args, **kwargs)
        monkeypatch.setattr(passes, name, spy)
    return taken


@pytest.mark.parametrize("in_stencil", [True, False], ids=["stencil", "colour"])
@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("run", [("auto", "cpu"), ("zpass", "cpu"), ("zfail", "cpu"),
                                 ("auto", "gpu")])
def test_the_mask_pass_gives_the_deferred_frames_masks(ctx, passes_taken, seed, run,
                                                       in_stencil):
    """Point, directional and spot lights together (scene_of: lights of every kind); the bits
    in the stencil where the 3 lights of seed 0 leave room for its counts (a floor and four
    closed convex casters: counts below 10 < 2^4), in a colour target for 4 or more lights,
    and always with `masks_in_stencil` off."""
    with Renderer(mixed_scene(seed, lights=3 + seed), ctx) as r:
        r.masks_in_stencil = in_stencil
        full = r.render(*run)
        assert passes_taken == ["shade"]
        masks = r.render(*run, outputs=MASKS)
        assert passes_taken == ["shade", "mask"]
        assert passes_taken.in_stencil == [in_stencil and seed == 0]
        lit_only = r.render(*run, outputs=("lit",))
        coverage_only = r.render(*run, outputs=("coverage",))
    assert_same_masks(masks, full, str(run))
    assert masks.image is None and masks.image_srgb is None and masks.stencil is None
    np.testing.assert_array_equal(lit_only.lit, full.lit)
    assert lit_only.coverage is None and coverage_only.lit is None
    np.testing.assert_array_equal(coverage_only.coverage, full.coverage)
    # some of every light's pixels are lit and some shadowed: the clears did something
    assert full.lit.any(axis=(1, 2)).all()
    assert (full.coverage & ~full.lit).any(axis=(1, 2)).all()


def test_a_full_page_of_lights_in_one_framebuffer(ctx, passes_taken):
    """LIGHTS_PER_PAGE lights: each light's count starts from the stencil the previous clear
    zeroed, so each light's mask is its own frame's."""
    scene = mixed_scene(5, lights=LIGHTS_PER_PAGE)
    with Renderer(scene, ctx) as r:
        masks = r.render(outputs=MASKS)
        full = r.render()
        alone = [r.render(lights=(light,), outputs=MASKS) for light in scene.lights[:4]]
    assert passes_taken[0] == "mask"
    assert_same_masks(masks, full)
    for i, one in enumerate(alone):
        np.testing.assert_array_equal(masks.lit[i], one.lit[0], err_msg=f"light {i}")


def test_more_lights_than_a_page_take_the_deferred_passes(ctx, passes_taken):
    scene = mixed_scene(2, lights=LIGHTS_PER_PAGE + 1)
    with Renderer(scene, ctx) as r:
        masks = r.render(outputs=MASKS)
        assert "mask" not in passes_taken
        full = r.render()
    assert_same_masks(masks, full)


def test_anything_but_masks_takes_the_deferred_passes(ctx, passes_taken):
    with Renderer(mixed_scene(0), ctx) as r:
        for outputs in (("lit", "image"), ("coverage", "image_srgb"), ("lit", "depth")):
            passes_taken.clear()
            r.render(outputs=outputs)
            assert passes_taken == ["shade"], outputs
        passes_taken.clear()
        r.render(outputs=MASKS, stencil=True)
        assert passes_taken == ["shade"]


def test_an_area_lights_samples_in_the_mask_pass(ctx, passes_taken):
    """An area light's samples are hard lights of the page: its counts (soft shadows) are the
    deferred frame's."""
    m = Material(diffuse=[0.7, 0.7, 0.7])
    scene = Scene(camera=Camera(eye=[0, 4, 7], target=[0, 0, 0]),
                  objects=[plane("floor", size=(10.0, 10.0), material=m),
                           sphere("ball", [0.2, 1.0, 0.0], 0.6, m, subdivisions=2)],
                  lights=[AreaLight("rect", center=[0, 4, 0], normal=[0, -1, 0],
                                    size=[1.5, 1.5], samples=16),
                          PointLight([2, 5, 1], intensity=0.5)],
                  width=96, height=72)
    with Renderer(scene, ctx) as r:
        masks = r.render(outputs=MASKS)
        full = r.render()
    assert passes_taken == ["mask", "shade"]
    assert_same_masks(masks, full)
    penumbra = (masks.lit_count[0] > 0) & (masks.lit_count[0] < 16)
    assert penumbra.any() and (masks.lit_count[0] == 0).any()


def _kinds(n: int):
    """n hard lights above the origin, point, spot and directional in turn."""
    kinds = [lambda k: PointLight([-2.0 + k, 6.0, 1.0 - 0.5 * k], intensity=0.3),
             lambda k: SpotLight([1.5 - k, 6.5, 1.5], [0.1 * k, -1.0, -0.3], cone_angle=45,
                                 intensity=0.3),
             lambda k: DirectionalLight([0.2 - 0.1 * k, -1.0, 0.3], intensity=0.3)]
    return [kinds[k % 3](k) for k in range(n)]


@pytest.mark.parametrize("lights", range(1, 7))
def test_every_light_count_the_stencil_holds(ctx, passes_taken, lights):
    """1 to 6 lights with the bits in the stencil (the count bits 6 to 1): the deferred
    frame's masks and the colour target's, for each method and silhouette path.  With shadows
    where the casters' bound (`count_bound`) fits below 2^(7 - lights): a box, a sphere and a
    floor (6) for up to 4 lights, the box under one triangle (3) for 5; without shadows (no
    counts) for 6."""
    m = Material(diffuse=[0.6, 0.6, 0.6])
    objects = [box("block", [0.3, 0.9, -0.2], [1.2, 0.6, 0.8], m)]
    if lights <= 4:
        objects += [plane("floor", size=(10.0, 10.0), material=m),
                    sphere("ball", [-0.8, 1.6, 0.6], 0.5, m, subdivisions=2)]
    else:
        objects.append(Object("sheet", [[-0.3, 2.2, -0.5], [0.8, 2.2, -0.6], [0.3, 2.3, 0.4]],
                              [[0, 1, 2]], m))
    scene = Scene(camera=Camera(eye=[0, 4, 7], target=[0, 0.5, 0]), objects=objects,
                  lights=_kinds(lights), width=96, height=72)
    shadows = lights <= 5
    with Renderer(scene, ctx) as r:
        assert shadows <= (r.count_bound < 2 ** (7 - lights))
        for run in (("auto", "cpu"), ("zpass", "cpu"), ("zfail", "cpu"), ("auto", "gpu")):
            passes_taken.clear()
            passes_taken.in_stencil.clear()
            full = r.render(*run, shadows=shadows)
            masks = r.render(*run, shadows=shadows, outputs=MASKS)
            r.masks_in_stencil = False
            colour = r.render(*run, shadows=shadows, outputs=MASKS)
            r.masks_in_stencil = True
            assert passes_taken == ["shade", "mask", "mask"], run
            assert passes_taken.in_stencil == [True, False], run
            assert_same_masks(masks, full, f"{run}, the stencil")
            assert_same_masks(colour, full, f"{run}, the colour target")
        faces = r.render(shadows=False, outputs=("lit",)).lit
    # every light lit somewhere and, with shadows, shadowed somewhere it faces
    assert full.lit.any(axis=(1, 2)).all()
    if shadows:
        assert (faces & ~full.lit).any(axis=(1, 2)).all()


def _slabs(lights: int) -> Scene:
    """A floor under 4 thin closed slabs stacked below `lights` point lights: z-pass counts of
    8 (each slab 2: its top and bottom cast) under all four."""
    m = Material(diffuse=[0.6, 0.6, 0.6])
    objects = [plane("floor", size=(12.0, 12.0), material=m)]
    objects += [box(f"slab{i}", [0.0, 1.0 + 0.5 * i, 0.0], [1.6, 0.1, 1.6], m)
                for i in range(4)]
    return Scene(camera=Camera(eye=[0, 7, 6], target=[0, 0, 0]), objects=objects,
                 lights=[PointLight([0.1 * k, 6.0, 0.1 * k], intensity=0.3)
                         for k in range(lights)], width=96, height=72)


def test_counts_that_reach_the_stencils_modulus_take_the_colour_target(ctx, passes_taken,
                                                                      monkeypatch):
    """4 lights leave 3 count bits (modulo 8); under four stacked slabs the z-pass count is 8.
    The scene's bound (10) says so, and the frame keeps its bits in a colour target: the
    deferred frame's masks.  Forced into the stencil the same frame reads those pixels lit
    (8 = 0 modulo 8): the bound is what keeps them right."""
    with Renderer(_slabs(4), ctx) as r:
        assert r.count_bound == 10
        full = r.render("zpass")
        masks = r.render("zpass", outputs=MASKS)
        assert passes_taken.in_stencil == [False]
        with monkeypatch.context() as forcing:
            forcing.setattr(Renderer, "_masks_fit_stencil", lambda *a: True)
            forced = r.render("zpass", outputs=MASKS)
        assert passes_taken.in_stencil == [False, True]
    assert_same_masks(masks, full)
    wrapped = forced.lit & ~full.lit
    assert wrapped.any(axis=(1, 2)).all()
    assert not (full.lit & ~forced.lit).any()
    with Renderer(_slabs(3), ctx) as r:   # 4 count bits: 10 < 16 fits
        full = r.render("zpass")
        masks = r.render("zpass", outputs=MASKS)
    assert passes_taken.in_stencil == [False, True, True]
    assert_same_masks(masks, full)


def test_negative_counts_stay_in_their_bits(ctx, passes_taken):
    """Forced z-pass with the eye inside a volume (below a sphere, straight under a
    directional light): counts of -2 where the view ray leaves it.  At a wall lit edge-on (n .
    l = 0: covered, not facing) the stored byte is 0x80 and -2 must not borrow the coverage bit
    (the counts' write mask): the deferred frame's coverage and masks."""
    m = Material(diffuse=[0.6, 0.6, 0.6])
    scene = Scene(camera=Camera(eye=[0.0, 1.0, 0.0], target=[3.0, 0.8, 0.3]),
                  objects=[plane("floor", size=(12.0, 12.0), material=m),
                           sphere("ball", [0.0, 3.0, 0.0], 0.8, m, subdivisions=2),
                           box("wall", [3.5, 1.0, 0.0], [1.0, 2.0, 3.0], m)],
                  lights=[DirectionalLight([0.0, -1.0, 0.0])], width=96, height=72)
    with Renderer(scene, ctx) as r:
        full = r.render("zpass", stencil=True)
        masks = r.render("zpass", outputs=MASKS)
        faces = r.render(shadows=False, outputs=("lit",)).lit[0]
    assert passes_taken.in_stencil == [True, True]
    assert_same_masks(masks, full)
    # the case the write mask is for: covered, not facing the light, a negative count
    assert (full.coverage & ~faces & (full.stencil[0] == -2)).sum() > 100


def test_the_stencil_layout():
    assert stencil.mask_layout(1) == (0x3F, (0x40,))
    assert stencil.mask_layout(3) == (0x0F, (0x40, 0x20, 0x10))
    assert stencil.mask_layout(6) == (0x01, (0x40, 0x20, 0x10, 0x08, 0x04, 0x02))
    for n in (0, 7):
        with pytest.raises(ValueError, match="1..6 lights"):
            stencil.mask_layout(n)


def test_without_stencil_export_the_bits_go_to_a_colour_target(ctx, passes_taken):
    """A GL without ARB_shader_stencil_export (some GPU drivers): the colour target."""
    with Renderer(mixed_scene(0), ctx) as r:
        # the GL's answer (`Pipeline.stencil_export`, looked up once and kept) taken as no
        r.pipeline.__dict__["stencil_export"] = False
        masks = r.render(outputs=MASKS)
        full = r.render()
    assert passes_taken.in_stencil == [False]
    assert_same_masks(masks, full)


def _facing32(normal, to_light, fused: bool) -> np.ndarray:
    """dot(normal, to_light) in float32 (k,) the way a shader evaluates it: each product and
    sum rounded (fused=False), or each product added exactly to the running sum before one
    rounding, as a compiler that fuses multiply-adds would."""
    n, d = normal.astype(np.float32), to_light.astype(np.float32)
    total = n[:, 0] * d[:, 0]
    for j in (1, 2):
        if fused:
            total = (n[:, j].astype(np.float64) * d[:, j] + total).astype(np.float32)
        else:
            total = total + n[:, j] * d[:, j]
    return total


def test_the_light_in_the_triangles_planes(ctx, passes_taken):
    """Triangles whose planes pass through the point light: n . (L - v0) is rounding noise, so
    its sign depends on how the float32 expression is evaluated.  The mask pass takes it per
    triangle in scene.vert, the shading pass per pixel in shade.frag; both evaluate it the
    same way (`precise`), so the masks are still the deferred frame's bit for bit."""
    rng = np.random.default_rng(7)
    light = np.array([0.31, 2.17, 0.23])
    tris = []
    for x in np.linspace(-1.6, 1.6, 14):
        for z in np.linspace(-1.6, 1.6, 14):
            n = rng.normal(size=3)
            n /= np.linalg.norm(n)
            centre = np.array([x, rng.uniform(-0.3, 0.3), z])
            centre -= n * np.dot(centre - light, n)          # into the plane through the light
            u = np.cross(n, [0.0, 1.0, 0.0] if abs(n[1]) < 0.9 else [1.0, 0.0, 0.0])
            u /= np.linalg.norm(u)
            w = np.cross(n, u)
            tris.append([centre + 0.11 * (np.cos(a) * u + np.sin(a) * w)
                         for a in (0.0, 2.1, 4.2)])
    corners = np.array(tris)
    # the renderer's own float32 normal and corner (geometry.py rounds the float64 values)
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    to_light = light.astype(np.float32) - corners[:, 0].astype(np.float32)
    plain, fused = (_facing32(normal, to_light, f) for f in (False, True))
    # the scene tells the evaluation orders apart: a shader that fused in one pass and not in
    # the other would light some of these triangles in one frame and not in the other
    assert (np.sign(plain) != np.sign(fused)).sum() >= 5
    faces = np.arange(3 * len(tris)).reshape(-1, 3)
    scene = Scene(camera=Camera(eye=[0.2, 6.0, 0.4], target=[0, 0, 0], up=[0, 0, -1]),
                  objects=[Object("fan", corners.reshape(-1, 3), faces)],
                  lights=[PointLight(light.tolist())], width=160, height=160)
    with Renderer(scene, ctx) as r:
        masks = r.render(outputs=MASKS)
        full = r.render()
    assert passes_taken == ["mask", "shade"]
    assert_same_masks(masks, full)
    assert full.lit.any() and (full.coverage & ~full.lit).any()


def test_back_face_culling_and_no_shadows(ctx, passes_taken):
    with Renderer(mixed_scene(1), ctx) as r:
        r.cull_back_faces = True
        culled = r.render(outputs=MASKS)
        culled_full = r.render()
        r.cull_back_faces = False
        facing = r.render(shadows=False, outputs=("lit",))
        facing_full = r.render(shadows=False)
    assert passes_taken == ["mask", "shade", "mask", "shade"]
    assert_same_masks(culled, culled_full)
    np.testing.assert_array_equal(facing.lit, facing_full.lit)


def test_a_moving_camera_and_the_ray_tracer(ctx, assert_masks_match):
    """Frames of one renderer from other eyes (the geometry re-expressed in each eye's frame):
    each mask-only frame within the mask budget of the ray tracer's."""
    scene = mixed_scene(3)
    with Renderer(scene, ctx) as r:
        for eye in ([0, 4, 9], [5, 3, 6], [-4, 6, -5]):
            camera = Camera(eye=eye, target=[0, 0.8, 0])
            masks = r.render(camera=camera, outputs=MASKS)
            assert_masks_match(masks, *raytrace.shadow_masks(scene.replace(camera=camera)),
                               str(eye))
