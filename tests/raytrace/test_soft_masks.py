"""The ray tracer's soft-shadow masks (raytrace.soft) and its Whitted image under area lights."""

from __future__ import annotations

import numpy as np
import pytest
from builders import (
    MATTE,
    OCCLUDER_CENTER,
    OCCLUDER_SIDE,
    SCENES,
    blocked_samples,
    floor_points,
    square_light,
    square_over_floor,
)

import raytrace
from raytrace.camera import primary_rays
from raytrace.tolerances import surface_offset
from shadowvol.cli.raytrace import main as raytrace_main
from shadowvol.primitives import plane
from shadowvol.scene import AreaLight, Camera, Material, PointLight, Scene
from shadowvol.scenefile import load_scene, save_scene


def test_one_sample_is_the_point_light():
    rect = square_light(1, seed=5)
    soft = raytrace.soft_masks(square_over_floor(rect))
    lit, cov = raytrace.shadow_masks(square_over_floor(PointLight(rect.positions[0])))
    np.testing.assert_array_equal(soft.lit_count[0], lit[0])
    np.testing.assert_array_equal(soft.lit, lit)
    np.testing.assert_array_equal(soft.coverage, cov)
    assert soft.samples.tolist() == [1] and lit[0].any() and (~lit[0] & cov).any()


@pytest.mark.parametrize("name", ["stack.toml", "whitted.toml"])
def test_hard_lights_count_one(name):
    scene = load_scene(SCENES / name).replace(width=64, height=48)
    soft = raytrace.soft_masks(scene)
    lit, cov = raytrace.shadow_masks(scene)
    np.testing.assert_array_equal(soft.lit, lit)
    assert soft.lit_count.max() <= 1 and soft.samples.tolist() == [1] * len(scene.lights)
    np.testing.assert_array_equal(soft.coverage, cov)
    assert not soft.penumbra.any()


@pytest.mark.parametrize("light", [
    square_light(16, pattern="halton"),
    AreaLight("disk", [0.0, 2.5, 0.0], normal=[0.2, -1.0, 0.0], radius=0.7, samples=16),
    AreaLight("sphere", [0.0, 2.5, 0.0], radius=0.6, samples=16, pattern="halton", seed=2),
], ids=["rect", "disk", "sphere"])
def test_outputs_fit_together(light):
    scene = square_over_floor(light, size=48)
    soft = raytrace.soft_masks(scene)
    count, n = soft.lit_count, soft.samples[:, None, None]
    assert count.dtype == np.uint16 and soft.visibility.dtype == np.float32
    assert (count <= n).all() and not (count > 0)[:, ~soft.coverage].any()
    assert not ((count > 0) & ~soft.facing).any()
    assert not (soft.umbra & soft.penumbra).any() and not (soft.umbra & soft.lit).any()
    np.testing.assert_array_equal(soft.lit, count == n)
    assert soft.umbra.any() and soft.penumbra.any() and soft.lit.any()
    # the per-sample hard masks add up to the count
    p, on_floor = floor_points(scene)
    blocked, margin = blocked_samples(p, light.positions)
    clear = on_floor & (margin.min(axis=-1) > 1e-5)
    expected = (~blocked).sum(axis=-1)
    np.testing.assert_array_equal(count[0][clear], expected[clear])


def test_one_sided_emission():
    """A rect light facing up lights nothing below it: not lit, not facing, so not umbra."""
    up = AreaLight("rect", [0.0, 2.5, 0.0], normal=[0.0, 1.0, 0.0], size=[1.2, 1.2], samples=4)
    soft = raytrace.soft_masks(square_over_floor(up, size=32))
    assert soft.coverage.any() and not soft.lit_count.any() and not soft.facing.any()
    assert not soft.umbra.any()


def test_sphere_light_through_the_floor():
    """A sphere light cut by the floor: the samples below it never reach the floor's top."""
    light = AreaLight("sphere", [0.3, 0.0, 0.2], radius=0.5, samples=64)
    floor = plane("floor", size=[8.0, 8.0], material=MATTE)
    scene = Scene(Camera([0.0, 4.0, 5.0], [0.0, 0.0, 0.0]), [floor], [light], width=32,
                  height=24)
    soft = raytrace.soft_masks(scene)
    above = int((light.positions[:, 1] > 0).sum())
    assert 0 < above < 64
    assert (soft.lit_count[0][soft.coverage] == above).all()
    assert soft.penumbra[0][soft.coverage].all() and soft.facing[0][soft.coverage].all()


def test_mask_file_holds_the_samples(tmp_path):
    scene = square_over_floor(square_light(16, pattern="halton"), size=32)
    scene = scene.replace(lights=scene.lights + (PointLight([0.0, 3.0, 0.0]),))
    save_scene(scene, tmp_path / "s.json")
    assert raytrace_main(["masks", str(tmp_path / "s.json"), "-o", str(tmp_path / "m.npz"),
                          "--no-png"]) == 0
    with np.load(tmp_path / "m.npz", allow_pickle=False) as data:
        np.testing.assert_array_equal(data["light_samples_0"], scene.lights[0].positions)
        np.testing.assert_array_equal(data["light_samples_1"], [[0.0, 3.0, 0.0]])
        assert data["light_samples_0"].dtype == np.float64
        soft = raytrace.soft_masks(scene)
        np.testing.assert_array_equal(data["lit"], soft.lit)


def test_whitted_direct_light_is_the_sum_of_the_samples():
    """max_depth 0 on a matte floor: each visible sample adds kd * radiance / N * (n·l)(cosine
    at the light), with both cosines l_y here (floor normal up, light normal down)."""
    light = square_light(16, seed=3, intensity=2.0)
    scene = square_over_floor(light, size=48)
    image = raytrace.render(scene, max_depth=0, progress=False)
    p, on_floor = floor_points(scene)
    blocked, margin = blocked_samples(p, light.positions)
    to_light = light.positions - p[..., None, :]
    ly = to_light[..., 1] / np.linalg.norm(to_light, axis=-1)
    expected = 0.8 * 2.0 / 16 * (np.where(blocked, 0.0, ly * ly)).sum(axis=-1)
    clear = on_floor & (margin.min(axis=-1) > 1e-3)  # Whitted's shadow rays start off the floor
    assert clear.sum() > 0.9 * on_floor.sum()
    np.testing.assert_allclose(image[..., 0][clear], expected[clear], rtol=1e-9, atol=1e-12)
    soft_levels = np.unique(np.round(image[..., 0][clear], 6))
    assert len(soft_levels) > 100  # a soft shadow, not two or three flat levels


def test_soft_shadow_seen_in_a_mirror():
    """A pure mirror behind the scene (z = -2.5, facing the camera): at max_depth 1 a mirror
    pixel shows the direct light of the floor point its reflected ray meets, soft shadow and
    all — the same sum over the samples as on the floor itself."""
    light = square_light(16, seed=2)
    base = square_over_floor(light, size=64)
    mirror = plane("mirror", point=[0.0, 1.5, -2.5], normal=[0.0, 0.0, 1.0], size=[8.0, 3.0],
                   material=Material(ambient=[0, 0, 0], diffuse=[0, 0, 0], specular=[0, 0, 0],
                                     reflectivity=1.0))
    scene = base.replace(objects=base.objects + (mirror,), max_depth=1)
    image = raytrace.render(scene, progress=False)[..., 0].ravel()
    o, d = primary_rays(scene.camera, scene.width, scene.height)
    t_mirror = (-2.5 - o[:, 2]) / d[:, 2]
    m = o + t_mirror[:, None] * d                      # where each pixel ray meets z = -2.5
    r = d * np.array([1.0, 1.0, -1.0])                 # reflected about the mirror's normal
    m = m + [0.0, 0.0, surface_offset(scene)]          # where Whitted starts the mirror ray
    t_floor = -m[:, 1] / r[:, 1]
    q = m + t_floor[:, None] * r
    q[:, 1] = 0.0
    t_occ = (1.0 - m[:, 1]) / r[:, 1]
    c = m + t_occ[:, None] * r                         # the reflected ray at the occluder's height
    t_occ_in = (1.0 - o[:, 1]) / d[:, 1]
    a = o + t_occ_in[:, None] * d                      # the primary ray there
    half = OCCLUDER_SIDE / 2

    def in_square(p):
        return (np.abs(p[:, 0] - OCCLUDER_CENTER[0]) <= half) & \
            (np.abs(p[:, 2] - OCCLUDER_CENTER[2]) <= half)

    on_mirror = (t_mirror > 0) & (m[:, 1] > 0) & (m[:, 1] < 3.0) & (np.abs(m[:, 0]) < 4.0) & \
        (t_floor > 0) & (np.abs(q[:, 0]) < 4.0) & (np.abs(q[:, 2]) < 4.0) & \
        ~(in_square(a) & (t_occ_in < t_mirror)) & ~(in_square(c) & (t_occ > 0) &
                                                  (t_occ < t_floor))
    blocked, margin = blocked_samples(q, light.positions)
    to_light = light.positions - q[:, None, :]
    ly = to_light[..., 1] / np.linalg.norm(to_light, axis=-1)
    expected = 0.8 / 16 * np.where(blocked, 0.0, ly * ly).sum(axis=-1)
    clear = on_mirror & (margin.min(axis=-1) > 1e-3)
    assert clear.sum() > 300
    np.testing.assert_allclose(image[clear], expected[clear], rtol=1e-9, atol=1e-12)
    shadowed = clear & (blocked.sum(axis=-1) > 0)
    assert (blocked[shadowed].sum(axis=-1) < 16).sum() > 20  # penumbra in the mirror
