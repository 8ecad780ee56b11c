"""Area lights in the scene model and in scene files: the samples, and the error of bad input."""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path

import numpy as np
import pytest
from builders import SCENES

from shadowvol import arealights, planes, primitives
from shadowvol.scene import (
    AreaLight,
    AreaSample,
    Camera,
    PointLight,
    Scene,
    SceneError,
    emission_cosine,
    hard_lights,
    light_samples,
)
from shadowvol.scenefile import load_scene, save_scene, scene_from_dict

HEAD = """
[camera]
eye = [0.0, 2.0, 5.0]
target = [0.0, 0.0, 0.0]

[[objects]]
type = "box"
"""


def load_error(tmp_path: Path, light: str) -> SceneError:
    path = tmp_path / "scene.toml"
    path.write_text(HEAD + "\n[[lights]]\n" + light)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert info.value.file == str(path)
    return info.value


RECT = 'type = "rect"\ncenter = [0.0, 3.0, 0.0]\nnormal = [0.0, -1.0, 0.0]\nsize = [1.0, 2.0]\n'


@pytest.mark.parametrize("extra, key, words", [
    ("samples = 0", "lights[0].samples", "1..65535"),
    ("samples = 70000", "lights[0].samples", "1..65535"),
    ("samples = 2.5", "lights[0].samples", "whole number"),
    ('pattern = "sobol"', "lights[0].pattern", "unknown pattern"),
    ("seed = -1", "lights[0].seed", ">= 0"),
    ("radius = 1.0", "lights[0].radius", "unknown key"),
    ("bogus = 1", "lights[0].bogus", "unknown key"),
])
def test_bad_rect_input(tmp_path, extra, key, words):
    err = load_error(tmp_path, RECT + extra + "\n")
    assert err.key == key and words in err.problem, err


@pytest.mark.parametrize("light, key, words", [
    (RECT.replace("[1.0, 2.0]", "[0.0, 2.0]"), "lights[0].size", "positive"),
    (RECT.replace("[0.0, -1.0, 0.0]", "[0.0, 0.0, 0.0]"), "lights[0].normal", "non-zero"),
    (RECT.replace("size = [1.0, 2.0]\n", ""), "lights[0].size", "missing"),
    ('type = "disk"\ncenter = [0.0, 3.0, 0.0]\nnormal = [0.0, -1.0, 0.0]\nradius = 0.0\n',
     "lights[0].radius", "> 0.0"),
    ('type = "disk"\ncenter = [0.0, 3.0, 0.0]\nradius = 1.0\n', "lights[0].normal", "missing"),
    ('type = "sphere"\ncenter = [0.0, 3.0, 0.0]\nradius = -1.0\n', "lights[0].radius", "> 0.0"),
    ('type = "sphere"\nradius = 1.0\n', "lights[0].center", "missing"),
    ('type = "sphere"\ncenter = [0.0, 3.0, nan]\nradius = 1.0\n', "lights[0].center",
     "non-finite"),
])
def test_bad_shape_input(tmp_path, light, key, words):
    err = load_error(tmp_path, light)
    assert err.key == key and words in err.problem, err


def test_bad_input_in_code():
    with pytest.raises(SceneError, match="radius: not a key of a rect light"):
        AreaLight("rect", [0, 0, 0], normal=[0, 1, 0], size=[1, 1], radius=1.0)
    with pytest.raises(SceneError, match="type: unknown area light shape 'tube'"):
        AreaLight("tube", [0, 0, 0], radius=1.0)
    with pytest.raises(SceneError, match="samples"):
        AreaLight("sphere", [0, 0, 0], radius=1.0, samples=True)


def test_the_documented_area_lights_load():
    text = (SCENES / "README.md").read_text()
    block = text.split("## Area lights\n\n```toml\n", 1)[1].split("```", 1)[0]
    lights = scene_from_dict(tomllib.loads(HEAD + block)).lights
    assert [lt.shape for lt in lights] == ["rect", "disk", "sphere", "polygon"]
    assert [lt.samples for lt in lights] == [16, 16, 16, 16]
    assert np.allclose(lights[3].normal, [0, -1, 0])   # counter-clockwise seen from below


def _rect(**kw):
    args = dict(shape="rect", center=[0.0, 3.0, 0.0], normal=[0.0, -2.0, 0.0], size=[2.0, 1.0],
                samples=16)
    args.update(kw)
    return AreaLight(**args)


@pytest.mark.parametrize("pattern", ["stratified", "halton"])
def test_samples_lie_on_the_shapes(pattern):
    rect = _rect(pattern=pattern)
    u, v = planes.default_plane_axes(rect.normal)
    local = rect.positions - rect.center
    assert np.allclose(local @ rect.normal, 0.0)
    assert np.all(np.abs(local @ u) <= 1.0) and np.all(np.abs(local @ v) <= 0.5)
    disk = AreaLight("disk", [1.0, 2.0, 3.0], normal=[1.0, 1.0, 0.0], radius=0.7, samples=64,
                     pattern=pattern)
    local = disk.positions - disk.center
    assert np.allclose(local @ disk.normal, 0.0)
    assert np.all(np.linalg.norm(local, axis=1) <= 0.7 + 1e-12)
    ball = AreaLight("sphere", [1.0, 2.0, 3.0], radius=0.5, samples=33, pattern=pattern)
    assert np.allclose(np.linalg.norm(ball.positions - ball.center, axis=1), 0.5)
    for light in (rect, disk, ball):
        assert light.positions.shape == (light.samples, 3) and light.positions.dtype == np.float64
        assert not light.positions.flags.writeable
        assert np.isclose(light.weights.sum(), 1.0)


@pytest.mark.parametrize("pattern", ["stratified", "halton"])
def test_polygon_samples_lie_in_the_polygon_evenly(pattern):
    """An L (three unit squares) tilted out of the axes: every sample on its plane and inside
    it; with the stratified 32 x 24 grid, each of its triangles holds its area's share of the
    samples up to 2 x 24: u picks the triangle, so every whole column of cells inside its
    u-interval puts 24 samples in it and only the two partial columns at its ends may not."""
    flat = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], float)
    tilt = np.array([[1.0, 0.0, 0.3], [0.0, 1.0, -0.2]])
    corner = np.array([5.0, 1.0, -2.0])
    light = AreaLight("polygon", None, vertices=flat @ tilt + corner, samples=768,
                      pattern=pattern, seed=2)
    local = np.linalg.lstsq(tilt.T, (light.positions - corner).T, rcond=None)[0].T
    assert np.abs(local @ tilt - (light.positions - corner)).max() < 1e-12
    x, y = local[:, 0], local[:, 1]
    assert ((x >= -1e-12) & (y >= -1e-12) & (x <= 2 + 1e-12) & (y <= 2 + 1e-12)
            & ((x <= 1 + 1e-12) | (y <= 1 + 1e-12))).all()
    if pattern == "stratified":
        assert arealights.grid_shape(768) == (32, 24)
        u, v = planes.default_plane_axes(light.normal)
        axes = np.stack([u, v], axis=1)
        f = (light.vertices - light.center) @ axes
        q = (light.positions - light.center) @ axes
        triangles = arealights.triangulate(f)
        counts, shares = [], []
        for a, b, c in f[triangles]:
            m = np.linalg.inv(np.stack([b - a, c - a], axis=1))
            st = (q - a) @ m.T
            s, t = st[:, 0], st[:, 1]
            counts.append(((s >= -1e-12) & (t >= -1e-12) & (s + t <= 1 + 1e-12)).sum())
            shares.append(abs(np.cross(np.r_[b - a, 0], np.r_[c - a, 0])[2]) / 2 / 3)
        assert sum(counts) >= 768
        assert np.abs(np.array(counts) - 768 * np.array(shares)).max() <= 2 * 24


def test_a_polygon_light_far_from_the_origin_is_the_same_light():
    """A polygon light moved 1e4 (a corner's coordinates ~1e4): accepted as planar, with the
    same normal, area and samples (moved) up to the rounding of coordinates of 1e4.  The
    Newell normal summed the corners' own cross products (~1e8 each) and refused it as 3e-9
    off its plane."""
    flat = np.array([[0, 0], [1.3, 0.2], [0.9, 1.1], [0.1, 0.8]], float)
    tilt = np.array([[0.8, 0.3, 0.5], [-0.2, 0.4, 0.9]])
    near = AreaLight("polygon", None, vertices=flat @ tilt, samples=16, seed=1)
    shift = np.array([1e4, -3e3, 1e4])
    far = AreaLight("polygon", None, vertices=flat @ tilt + shift, samples=16, seed=1)
    assert np.abs(far.normal - near.normal).max() < 1e-10
    assert np.abs(far.positions - shift - near.positions).max() < 1e-9


def test_stratified_puts_one_sample_per_cell():
    rect = _rect(samples=32)  # 8 x 4: more cells along u, the longer side
    u, v = planes.default_plane_axes(rect.normal)
    local = rect.positions - rect.center
    i = np.floor((local @ u + 1.0) / 2.0 * 8).astype(int)
    j = np.floor((local @ v + 0.5) / 1.0 * 4).astype(int)
    assert sorted(zip(i.tolist(), j.tolist())) == [(a, b) for a in range(8) for b in range(4)]
    assert arealights.grid_shape(32) == (8, 4) and arealights.grid_shape(7) == (7, 1)


def test_samples_are_deterministic_and_seeded():
    a, b = _rect(seed=3), _rect(seed=3)
    np.testing.assert_array_equal(a.positions, b.positions)
    assert not np.array_equal(a.positions, _rect(seed=4).positions)
    h = _rect(pattern="halton")
    np.testing.assert_array_equal(h.positions, _rect(pattern="halton").positions)
    uv = arealights.unit_square(4, "halton", 0)
    np.testing.assert_allclose(uv, [[0.5, 1 / 3], [0.25, 2 / 3], [0.75, 1 / 9], [0.125, 4 / 9]])
    # dataclasses.replace recomputes the samples
    assert dataclasses.replace(a, samples=4).positions.shape == (4, 3)


def test_hard_lights_carry_the_samples():
    rect = _rect()
    hard = hard_lights(rect)
    assert len(hard) == 16 and all(isinstance(h, AreaSample) for h in hard)
    np.testing.assert_array_equal([h.position for h in hard], rect.positions)
    assert np.isclose(sum(h.intensity for h in hard), rect.intensity)
    assert hard[0].cone_angle == 90.0 and np.allclose(hard[0].direction, [0, -1, 0])
    # the cosine at the light: 1 straight below the sample, 0 level with it, clamped behind
    to_light = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    np.testing.assert_allclose(emission_cosine(hard[0], to_light), [1.0, 0.0, 0.0])
    ball = AreaLight("sphere", [0.0, 3.0, 0.0], radius=0.5, samples=4)
    assert all(type(h) is PointLight for h in hard_lights(ball))
    assert emission_cosine(hard_lights(ball)[0], to_light) == 1.0
    point = PointLight([1.0, 2.0, 3.0])
    assert hard_lights(point) == (point,)
    np.testing.assert_array_equal(light_samples(point), [[1.0, 2.0, 3.0]])
    assert light_samples(rect) is rect.positions


def test_sphere_light_may_intersect_a_mesh():
    """Allowed: the scene builds, its samples inside the box are kept (the renderers shadow
    them like any point light inside a box; tests/raytrace/test_soft_masks.py checks what a
    surface outside gets)."""
    box = primitives.box("b", center=[0.0, 0.0, 0.0], size=[1.0, 1.0, 1.0])
    light = AreaLight("sphere", [0.0, 0.5, 0.0], radius=0.5, samples=16)
    scene = Scene(Camera([0.0, 2.0, 5.0], [0.0, 0.0, 0.0]), [box], [light])
    inside = np.all(np.abs(scene.lights[0].positions) <= 0.5, axis=1)
    assert 0 < inside.sum() < 16


def test_save_scene_keeps_the_samples(tmp_path):
    scene = Scene(Camera([0.0, 2.0, 5.0], [0.0, 0.0, 0.0]), [primitives.box("b")],
                  [_rect(seed=7, pattern="halton"),
                   AreaLight("disk", [0, 3, 0], normal=[0, -1, 0], radius=0.5, samples=5),
                   AreaLight("sphere", [0, 3, 0], radius=0.5, samples=3, color=[1, 0.5, 0],
                             intensity=2.0)])
    save_scene(scene, tmp_path / "s.json")
    copy = load_scene(tmp_path / "s.json")
    for a, b in zip(scene.lights, copy.lights):
        np.testing.assert_array_equal(a.positions, b.positions)
        np.testing.assert_array_equal(a.radiance, b.radiance)
