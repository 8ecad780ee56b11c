"""`shadowvol shadowmap`: a shadow map against the exact shadow.  Its error falls with the
resolution; no bias is all acne, a large one peter-panning; the split adds up; the command's
JSON, picture, plot and bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest
from builders import ROOT

from shadowvol.cli.main import main as shadowvol_main
from shadowvol.compare.shadowmaps import ShadowMapper
from shadowvol.primitives import box, plane
from shadowvol.raster import shadowmap
from shadowvol.scene import Camera, DirectionalLight, PointLight, Scene
from shadowvol.scenefile import load_scene

pytestmark = pytest.mark.gl
STACK = ROOT / "scenes" / "stack.toml"


def _plate_over_floor(light) -> Scene:
    """A thin plate 0.05 above a floor: its shadow touches its contact region, where a large
    bias lets the light through (peter-panning)."""
    return Scene(camera=Camera(eye=[3, 4, 4], target=[0, 0, 0], fov_y=40),
                 objects=[plane("floor", [0, 0, 0], [0, 1, 0], [6, 6]),
                          box("plate", [0, 0.1, 0], [1.5, 0.05, 1.5])],
                 lights=[light], width=160, height=120)


@pytest.mark.parametrize("light", [0, 1], ids=["point", "directional"])
def test_the_error_falls_with_the_resolution(ctx, light):
    scene = load_scene(STACK).replace(width=160, height=120)
    with ShadowMapper(scene, light, ctx) as mapper:
        wrong = [mapper.measure(n, 0.01).counts()["misclassified"] for n in (256, 1024, 4096)]
    assert wrong[0] > wrong[1] > wrong[2], wrong
    assert wrong[2] < 0.002 * mapper.compared.sum()


@pytest.mark.parametrize("light", [PointLight([1.0, 6.0, 0.5]),
                                   DirectionalLight([-0.3, -1.0, -0.2])],
                         ids=["point", "directional"])
def test_no_bias_is_acne_and_a_large_bias_peter_panning(ctx, light):
    with ShadowMapper(_plate_over_floor(light), 0, ctx) as mapper:
        none, usual, huge = (mapper.measure(2048, b).counts() for b in (0.0, 0.002, 0.2))
        assert none["acne"] > 0.1 * none["pixels"]            # lit surfaces shadow themselves
        assert usual["acne"] < 0.01 * usual["pixels"]
        assert huge["peter_panning"] > 10 * max(usual["peter_panning"], 1)
        for c in (none, usual, huge):
            assert c["misclassified"] == c["acne"] + c["peter_panning"]
        result = mapper.measure(512, 0.002, pcf=3)
        assert not (result.acne & result.peter_panning).any()
        assert (result.lit_exact <= result.compared).all()
        assert result.picture().shape[1] > 3 * 160


def test_the_map_stores_the_linear_distance_from_the_light(ctx):
    """A floor under a point light: every texel's depth is the floor point's distance from
    the light over the far distance, to the 24-bit depth buffer's resolution."""
    scene = _plate_over_floor(PointLight([0.0, 3.0, 0.0])).replace(
        objects=[plane("floor", [0, 0, 0], [0, 1, 0], [6, 6])])
    points = np.array([[x, 0.0, z] for x in (-2, 0, 2) for z in (-2, 0, 2)], float)
    view = shadowmap.fit(scene, scene.lights[0], points)
    depth = shadowmap.depth_map(ctx, scene, view, 256)
    uv = view.texel_coordinates(points)
    texel = depth[np.minimum((uv[:, 1] * 256).astype(int), 255),
                  np.minimum((uv[:, 0] * 256).astype(int), 255)]
    assert np.abs(texel - view.depth(points)).max() < 0.01   # within a texel's slope
    assert np.allclose(view.depth(points), np.linalg.norm(points - [0, 3, 0], axis=1)
                       / view.depth_range[1])


def test_the_command_writes_the_counts_the_picture_and_the_plot(tmp_path, capsys):
    scene = tmp_path / "stack.toml"
    scene.write_text(STACK.read_text().replace("width = 640", "width = 96")
                     .replace("height = 480", "height = 72"))
    args = ["shadowmap", str(scene), "-o", str(tmp_path / "s.png"), "--resolution", "512",
            "--bias", "0.001", "--pcf", "3", "--json", str(tmp_path / "s.json"), "--plot",
            str(tmp_path / "p.png")]
    assert shadowvol_main(args) == 0
    counts = json.loads((tmp_path / "s.json").read_text())
    assert {"misclassified", "acne", "peter_panning", "pixels"} <= set(counts)
    assert counts["misclassified"] == counts["acne"] + counts["peter_panning"] > 0
    assert (tmp_path / "s.png").stat().st_size > 0 and (tmp_path / "p.png").stat().st_size > 0
    assert f"{counts['misclassified']} of {counts['pixels']} pixels" in capsys.readouterr().out


@pytest.mark.parametrize("extra, words", [
    (["--pcf", "0"], "--pcf: must be 1..15"),
    (["--resolution", "8"], "--resolution: must be 16..8192"),
    (["--bias", "nan"], "--bias: must be a finite number"),
    (["--light", "5"], "the scene has 2 lights (0..1), not 5"),
])
def test_bad_input_is_one_line_and_exit_2(extra, words, tmp_path, capsys):
    args = ["shadowmap", str(STACK), "-o", str(tmp_path / "s.png"), *extra]
    assert shadowvol_main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0], err
    assert not (tmp_path / "s.png").exists()


def test_a_light_among_the_visible_points_needs_a_cube_map(tmp_path, capsys):
    assert shadowvol_main(["shadowmap", str(ROOT / "scenes" / "cage.toml"), "-o",
                           str(tmp_path / "s.png")]) == 2
    assert "cube map" in capsys.readouterr().err
