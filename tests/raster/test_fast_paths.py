"""The renderer's shortcuts must not change a single lit pixel.

- Halved z-pass sides (`CpuVolumes.draw_sides(halve=True)`): a caster whose edge multiplicities
  are all even draws each side quad once instead of twice.  The stencil is then 0 exactly where
  the full count was 0.
- The z-pass clip box (`methods.zpass_clip_planes`): z-pass side quads clipped to the box of
  the near rectangle and the casters; counts at covered pixels are unchanged.

So the lit masks and images must be bit-identical to the frames without them, and the ray
tracer's masks still match within the budget.
"""

from __future__ import annotations

import numpy as np
import pytest

import raytrace
from shadowvol.primitives import box, mesh, plane, sphere
from shadowvol.raster import passes
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import (
    Camera,
    DirectionalLight,
    Material,
    PointLight,
    Scene,
    SpotLight,
)


def random_scene(seed: int) -> Scene:
    """A floor (open: odd multiplicities), closed spheres and boxes (even), and one open sheet
    that closed meshes may overlap; random lights of every kind above the scene."""
    rng = np.random.default_rng(seed)
    objects = [plane("floor", size=[12, 12])]
    for i in range(4):
        c = [rng.uniform(-3, 3), rng.uniform(0.5, 2.0), rng.uniform(-3, 2)]
        if i % 2:
            objects.append(sphere(f"s{i}", c, rng.uniform(0.3, 0.8), subdivisions=2))
        else:
            objects.append(box(f"b{i}", c, rng.uniform(0.3, 1.2, 3)))
    # an open, non-closed triangle fan (odd multiplicities on its border)
    v = np.array([[0, 2.5, 0], [1, 2.5, 0.3], [0.3, 2.6, 1], [-0.8, 2.4, 0.5]], float)
    objects.append(mesh("fan", v + [rng.uniform(-1, 1), 0, rng.uniform(-1, 1)],
                        np.array([[0, 1, 2], [0, 2, 3]]), Material()))
    lights = [PointLight([rng.uniform(-4, 4), rng.uniform(5, 8), rng.uniform(-2, 4)]),
              DirectionalLight(direction=[rng.uniform(-0.5, 0.5), -1, rng.uniform(-0.5, 0.5)]),
              SpotLight([rng.uniform(-2, 2), 6, 2], [0, -1, -0.3], cone_angle=50)]
    return Scene(camera=Camera(eye=[0, 4, 9], target=[0, 0.8, 0]), objects=objects,
                 lights=lights, width=128, height=96)


def test_closed_meshes_are_halvable_open_ones_are_not(ctx):
    scene = random_scene(0)
    with Renderer(scene, ctx) as r:
        vols = r.volumes("cpu")
        vols.prepare(np.array([1.0, 7.0, 2.0, 1.0]))
        repeats = {scene.objects[i].name: vols._sides[i][2] for i in vols._sides}
    assert repeats["floor"] == 1 and repeats["fan"] == 1
    assert all(repeats[o.name] == 2 for o in scene.objects if o.name[0] in "sb")


@pytest.mark.parametrize("seed", range(6))
def test_halved_sides_give_identical_masks(ctx, seed, monkeypatch, assert_masks_match):
    scene = random_scene(seed)
    calls = []
    original = passes.count_signed

    def spy(*args, halve=False, **kw):
        calls.append(halve)
        return original(*args, halve=halve, **kw)

    monkeypatch.setattr(passes, "count_signed", spy)
    with Renderer(scene, ctx) as r:
        halved = r.render("auto", "cpu")
        full = r.render("auto", "cpu", stencil=True)   # counts asked for: never halved
    assert calls == [True] * 3 + [False] * 3
    np.testing.assert_array_equal(halved.lit, full.lit)
    np.testing.assert_array_equal(halved.image, full.image)
    ref_lit, ref_cov = raytrace.shadow_masks(scene)
    assert_masks_match(halved, ref_lit, ref_cov, f"seed {seed}")


@pytest.mark.parametrize("silhouettes", ["cpu", "gpu"])
@pytest.mark.parametrize("method", ["zpass", "auto"])
@pytest.mark.parametrize("seed", range(4))
def test_zpass_clip_box_gives_identical_masks(ctx, seed, method, silhouettes, monkeypatch):
    scene = random_scene(seed)
    if seed % 2:   # the eye among the casters, looking across the floor
        scene = scene.replace(camera=Camera(eye=[0.5, 1.0, 1.0], target=[-2, 0.5, -3]))
    original = passes.count_signed
    boxes = []

    def spy(*args, clip_planes=None, **kw):
        boxes.append(clip_planes)
        return original(*args, clip_planes=clip_planes, **kw)

    def unclipped(*args, clip_planes=None, **kw):
        return original(*args, clip_planes=None, **kw)

    with Renderer(scene, ctx) as r:
        monkeypatch.setattr(passes, "count_signed", spy)
        clipped = r.render(method, silhouettes)
        monkeypatch.setattr(passes, "count_signed", unclipped)
        full = r.render(method, silhouettes)
    assert all(b is not None and b.shape == (6, 4) for b in boxes) and len(boxes) == 3
    np.testing.assert_array_equal(clipped.lit, full.lit)
    np.testing.assert_array_equal(clipped.image, full.image)


def test_the_clip_box_is_off_when_counts_are_returned(ctx, monkeypatch):
    boxes = []
    original = passes.count_signed

    def spy(*args, clip_planes=None, **kw):
        boxes.append(clip_planes)
        return original(*args, clip_planes=clip_planes, **kw)

    monkeypatch.setattr(passes, "count_signed", spy)
    with Renderer(random_scene(0), ctx) as r:
        r.render("zpass", stencil=True)
    assert boxes == [None] * 3
