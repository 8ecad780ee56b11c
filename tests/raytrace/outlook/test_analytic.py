"""`raytrace render --integrator analytic` (raytrace.outlook.analytic): the diffuse light of
area lights from the exact visible region, the limit of Whitted's sampled direct light.

- against Whitted's direct light (max_depth 0) with 16 .. 1024 stratified samples: the mean
  error over the floor falls with N (the slope printed) and is small at 1024;
- without occluder, against the measure's closed form (a disk seen from its axis) and a dense
  midpoint grid (a rect, every floor pixel);
- `scenes/soft.toml` twice: the same image bit for bit, and a flat lit region without
  variance; a sphere light refused in one line naming the file.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from builders import LIGHT_SIDE, LIGHT_Y, floor_points, square_light, square_over_floor

from raytrace import polygons
from raytrace.outlook import analytic, whitted
from shadowvol.scenefile import load_scene

pytest.importorskip("shapely", reason="exact soft shadows need shapely: pip install 'shadowvol[exact]' (the test extra has it)")


def _floor_error(samples: int) -> float:
    scene = square_over_floor(square_light(samples), size=40)
    exact = analytic.render(scene)
    sampled = whitted.render(scene, max_depth=0)
    _, floor = floor_points(scene)
    return float(np.abs(exact - sampled)[floor].mean())


def test_the_sampled_direct_light_converges_to_the_analytic_one(capsys):
    ns = (16, 64, 256, 1024)
    errors = [_floor_error(n) for n in ns]
    slope = np.polyfit(np.log(ns), np.log(errors), 1)[0]
    with capsys.disabled():
        print(f"\nanalytic vs Whitted: mean error {errors} at N = {ns}, slope {slope:.2f}")
    assert all(b < a for a, b in zip(errors, errors[1:]))
    assert slope < -0.5 and errors[-1] < 2e-4


def test_the_disk_measure_from_its_axis_is_the_closed_form():
    """cos cos over a disk of radius R from its axis at height c: pi c^2 ln(1 + R^2/c^2)."""
    R, c = 0.7, 1.3
    square = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0]])
    axes = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])        # normal u x v = (0, -1, 0)
    eye = np.array([[0.0, -c, 0.0]])
    got = polygons.disk_ring_measures(square, np.zeros(5, int), 1, R, eye,
                                      np.array([[0.0, 1.0, 0.0]]), np.zeros(3), axes,
                                      direct=True)[2]
    assert got[0] == pytest.approx(math.pi * c * c * math.log1p(R * R / (c * c)), rel=1e-12)


def test_without_occluder_the_image_is_the_light_s_measure():
    scene = square_over_floor(square_light(4), size=24)
    scene = scene.replace(objects=[scene.objects[0]])
    image = analytic.render(scene)
    p, floor = floor_points(scene)
    n = 600
    s = (np.arange(n) + 0.5) / n * LIGHT_SIDE - LIGHT_SIDE / 2
    x, z = (a.ravel() for a in np.meshgrid(s, s))
    pts = p[floor]
    c2 = (LIGHT_Y - pts[:, 1])[:, None] ** 2
    d2 = (x[None] - pts[:, 0:1]) ** 2 + (z[None] - pts[:, 2:3]) ** 2 + c2
    measure = (c2 / d2).mean(axis=1)               # cos cos averaged over the light
    mat = scene.objects[0].material
    want = np.asarray(mat.ambient) * scene.ambient + np.asarray(mat.diffuse) * measure[:, None]
    assert np.abs(image[floor] - want).max() < 1e-6


def test_soft_scene_has_no_sample_noise():
    """Twice the same image, bit for bit; and the floor (no specular term) the same whatever
    the light's sample layout (seed, count, pattern), to float64 rounding, where Whitted's
    images differ by the sample noise."""
    import dataclasses

    from raytrace.groundtruth import ground_truth

    scene = load_scene("scenes/soft.toml").replace(width=80, height=60)
    a, b = analytic.render(scene), analytic.render(scene)
    assert np.array_equal(a, b)
    light = scene.lights[0]
    layouts = [scene.replace(lights=[dataclasses.replace(light, **kw)])
               for kw in ({}, {"seed": 7}, {"samples": 16, "pattern": "halton"})]
    floor = ground_truth(scene, outputs=("object_id",)).object_id == 1
    lit = floor & (a.sum(axis=-1) > 3 * 0.2)                   # some light reaches them
    assert lit.sum() > 1000
    exact = np.stack([analytic.render(s)[lit] for s in layouts])
    # the same to float64 rounding (a few 1e-16 of the values), whatever the layout
    assert np.abs(exact - exact[0]).max() <= 1e-14 * np.abs(exact).max()
    sampled = np.stack([whitted.render(s, max_depth=0)[lit] for s in layouts])
    assert np.abs(sampled - sampled[0]).max() > 1e-3


def test_a_sphere_light_is_refused(tmp_path, capsys):
    from shadowvol.cli.raytrace import main

    text = open("scenes/soft.toml").read().replace('type = "rect"', 'type = "sphere"')
    text = text.replace('normal = [0.0, -1.0, 0.0]\nsize = [1.6, 1.6]', "radius = 0.5")
    scene = tmp_path / "s.toml"
    scene.write_text(text)
    code = main(["render", str(scene), "-o", str(tmp_path / "a.png"), "--integrator",
                 "analytic"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "s.toml" in err[0] and "lights[0]" in err[0]


def test_the_command_writes_the_same_png_twice_and_refuses_spp(tmp_path, capsys):
    from shadowvol.cli.raytrace import main

    text = open("scenes/soft.toml").read().replace("width = 640", "width = 48") \
        .replace("height = 480", "height = 36")
    scene = tmp_path / "soft.toml"
    scene.write_text(text)
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    for out in (a, b):
        assert main(["render", str(scene), "-o", str(out), "--integrator", "analytic"]) == 0
    assert a.read_bytes() == b.read_bytes()
    capsys.readouterr()
    code = main(["render", str(scene), "-o", str(a), "--integrator", "analytic", "--spp", "4"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--spp" in err[0]
