"""The course's exercises as commands: `raytrace exercise plane|tir` prints the worked solution
computed with the ray tracer's own formulas and draws it; `shadowvol planar` writes planar
projected shadows."""

from __future__ import annotations

import numpy as np
import pytest
from builders import SCENES
from PIL import Image

from raytrace import exercise
from shadowvol.cli.main import main as shadowvol_main
from shadowvol.cli.raytrace import main as raytrace_main
from shadowvol.io import load_masks
from shadowvol.raster.planar.draw import render_planar
from shadowvol.scenefile import load_scene


def test_ray_plane_exercise_solution():
    s = exercise.solve_plane()
    assert s.lam == pytest.approx(1.0) and np.allclose(s.hit, (4.0, 4.0))
    assert s.distance == pytest.approx(0.0)       # the plane x - y = 0 passes the origin
    text = exercise.plane_text(s)
    assert "λ = (0 − 2.82843) / (-2.82843) = 1" in text
    assert "= (4, 4)" in text and "on the plane" in text
    miss = exercise.solve_plane(direction=(1.0, 1.0))   # parallel to the plane: a miss
    assert not np.isfinite(miss.lam) and "misses" in exercise.plane_text(miss)


def test_tir_exercise():
    rays = exercise.solve_tir()
    assert exercise.critical_angle() == pytest.approx(41.8103, abs=1e-4)
    assert [r.tir for r in rays] == [a > exercise.critical_angle() for a in exercise.TIR_ANGLES]
    for r in rays:
        if r.tir:      # mirror reflection: the same angle, back into the glass (downward)
            assert r.out_angle == pytest.approx(r.angle) and r.out[1] < 0
        else:          # Snell: 1.5 sin θ1 = sin θ2, into the air (upward)
            assert np.sin(np.radians(r.out_angle)) == pytest.approx(
                1.5 * np.sin(np.radians(r.angle)))
            assert r.out[1] > 0


@pytest.mark.parametrize("name, expect", [("plane", "= (4, 4)"), ("tir", "critical angle")])
def test_exercise_command(name, expect, tmp_path, capsys):
    out = tmp_path / f"{name}.png"
    assert raytrace_main(["exercise", name, "-o", str(out)]) == 0
    assert expect in capsys.readouterr().out
    with Image.open(out) as im:
        assert im.format == "PNG" and np.asarray(im.convert("RGB")).std() > 10
    assert raytrace_main(["exercise", name, "-o", str(tmp_path / "x.jpg")]) == 2
    assert not (tmp_path / "x.jpg").exists()


@pytest.mark.gl
def test_planar_command_writes_the_projected_shadows(tmp_path, ctx):
    path = SCENES / "planar.toml"
    scene = load_scene(path)
    assert shadowvol_main(["planar", str(path), "-o", str(tmp_path / "p.png"),
                           "--masks", str(tmp_path / "p.npz")]) == 0
    lit, coverage = load_masks(tmp_path / "p.npz")
    expected = render_planar(scene, ctx=ctx)
    assert (lit == expected.lit).all() and (coverage == expected.coverage).all()
    assert (~lit & coverage).any()                      # a shadow on the floor
    with Image.open(tmp_path / "p.png") as im:
        assert im.size == (scene.width, scene.height)
    assert shadowvol_main(["planar", str(path), "-o", str(tmp_path / "q.png"),
                           "--receiver", "no such object"]) == 2
    assert shadowvol_main(["planar", str(path), "-o", str(tmp_path / "q.png"),
                           "--receiver", "ball"]) == 2     # a sphere is no plane
    assert shadowvol_main(["planar", str(tmp_path / "missing.toml"), "-o",
                           str(tmp_path / "q.png")]) == 2
    assert shadowvol_main(["planar", str(path), "-o", str(tmp_path / "q.jpg")]) == 2
    assert not (tmp_path / "q.png").exists() and not (tmp_path / "q.jpg").exists()
