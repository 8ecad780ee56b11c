"""`raytrace render --integrator path` and `raytrace radiosity`; emissive materials in scene
files; the ladder picture's parts."""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest
from builders import CORNELL, cornell
from PIL import Image

from shadowvol.cli.raytrace import main
from shadowvol.course import ladder
from shadowvol.scene import SceneError
from shadowvol.scenefile import load_scene, save_scene


@pytest.fixture
def small_cornell(tmp_path):
    data = CORNELL.read_text().replace("width = 256", "width = 24").replace("height = 256",
                                                                            "height = 24")
    path = tmp_path / "cornell.toml"
    path.write_text(data)
    return path


def test_path_render_writes_png_and_exr_and_is_reproducible(small_cornell, tmp_path):
    a, b, exr = tmp_path / "a.png", tmp_path / "b.png", tmp_path / "a.exr"
    args = ["render", str(small_cornell), "--integrator", "path", "--spp", "2", "--seed", "3"]
    assert main(args + ["-o", str(a), "--exr", str(exr)]) == 0
    assert main(args + ["-o", str(b)]) == 0
    assert a.read_bytes() == b.read_bytes()
    pixels = np.asarray(Image.open(a))
    assert pixels.shape == (24, 24, 3) and pixels.max() > 100
    data = exr.read_bytes()
    assert struct.unpack("<i", data[:4])[0] == 20000630  # the OpenEXR magic number
    assert b"chlist" in data and len(data) > 24 * 24 * 12


def test_radiosity_writes_both_displays(small_cornell, tmp_path, capsys):
    out, flat = tmp_path / "r.png", tmp_path / "f.png"
    assert main(["radiosity", str(small_cornell), "--level", "1", "--rays", "32", "-o",
                 str(out), "--flat", str(flat)]) == 0
    err = capsys.readouterr().err
    assert "patches" in err and "iterations" in err
    smooth, blocky = np.asarray(Image.open(out)), np.asarray(Image.open(flat))
    assert smooth.shape == blocky.shape == (24, 24, 3)
    assert not np.array_equal(smooth, blocky)


@pytest.mark.parametrize("extra", [["--level", "-1"], ["--rays", "0"], ["--tol", "0"],
                                   ["--shots", "0"], ["--level", "40"]])
def test_radiosity_bad_options_exit_2(small_cornell, tmp_path, extra, capsys):
    assert main(["radiosity", str(small_cornell), "-o", str(tmp_path / "x.png")] + extra) == 2
    assert "error:" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize("extra", [["--spp", "0"], ["--max-depth", "0"]])
def test_path_bad_options_exit_2(small_cornell, tmp_path, extra):
    assert main(["render", str(small_cornell), "--integrator", "path", "-o",
                 str(tmp_path / "x.png")] + extra) == 2


def test_unwritable_output_is_bad_input_naming_the_path(small_cornell, tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(["radiosity", str(small_cornell), "--level", "0", "--rays", "8", "-o",
                 str(blocker / "x.png")]) == 2  # an output path is input (cli.status)
    assert capsys.readouterr().err.strip().splitlines()[-1] == \
        f"error: {blocker / 'x.png'}: cannot write: {blocker} is not a folder"


@pytest.mark.parametrize("value, message", [("[1, -1, 0]", "must be >= 0"),
                                            ("[1, 2]", "expected 3 numbers"),
                                            ('"bright"', "expected 3 numbers")])
def test_bad_emission_names_the_key(tmp_path, value, message):
    text = CORNELL.read_text().replace("emission = [17.1983", "emission = [9")
    start = text.index("[materials.light]")
    end = text.index("\n[", start + 1)
    block = text[start:end]
    lines = [f"emission = {value}" if line.startswith("emission") else line
             for line in block.splitlines()]
    path = tmp_path / "bad.toml"
    path.write_text(text[:start] + "\n".join(lines) + text[end:])
    with pytest.raises(SceneError, match=rf"materials\.light\.emission.*{message}"):
        load_scene(path)


def test_emission_survives_save_and_load(tmp_path):
    scene = cornell(8)
    save_scene(scene, tmp_path / "c.json")
    again = load_scene(tmp_path / "c.json")
    light = [o for o in again.objects if o.name == "light"][0]
    np.testing.assert_array_equal(light.material.emission,
                                  [o for o in scene.objects if o.name == "light"][0]
                                  .material.emission)
    assert "emission" in json.loads((tmp_path / "c.json").read_text())["objects"][0]["material"]


def test_cornell_scene_is_the_published_box():
    scene = cornell(8)
    names = [o.name for o in scene.objects]
    assert names == ["floor", "ceiling", "back wall", "green wall", "red wall", "light",
                     "short block", "tall block"]
    light = scene.objects[names.index("light")]
    lo, hi = light.vertices.min(axis=0), light.vertices.max(axis=0)
    np.testing.assert_allclose([lo, hi], [[213.0, 548.8, 227.0], [343.0, 548.8, 332.0]])
    red = scene.objects[names.index("red wall")].material.diffuse
    green = scene.objects[names.index("green wall")].material.diffuse
    assert red[0] > 5 * red[1] and green[1] > 3 * green[0]
    assert scene.camera.fov_y == pytest.approx(39.3076, abs=1e-3)


def test_ladder_bleeds_colour_only_in_the_global_rungs():
    """The white back wall beside the red wall is redder than beside the green wall in the
    path-traced, photon-mapped and radiosity rungs (colour bleeding), and not in the Whitted
    and direct-light rungs."""
    scene = cornell(32)
    settings = ladder.Settings(spp=64, level=2, rays=256, photons=40_000, k=50,
                               supersample=1)
    images, info = ladder.rungs(scene, settings)
    assert len(images) == len(ladder.RUNGS) == 6
    assert [name.split()[1] for name, _ in ladder.RUNGS] == [
        "local", "Whitted", "direct", "path", "photon", "radiosity"]
    # back wall: the middle rows, columns just inside the side walls (red left, green right)
    left, right = images[0].shape[1] * 9 // 32, images[0].shape[1] * 23 // 32
    rows = slice(6, 12)

    def redness(image, col):
        patch = image[rows, col - 1:col + 2]
        return float(patch[..., 0].mean() / patch[..., 1].mean())

    for rung in (1, 2):  # Whitted and direct light: no bounce off the red wall
        assert redness(images[rung], left) / redness(images[rung], right) == \
            pytest.approx(1.0, abs=0.02), rung
    for rung in (3, 4, 5):
        assert redness(images[rung], left) / redness(images[rung], right) > 1.15, rung
    shown = ladder.display(images, np.array(info["white_balance"]))
    assert all(p.dtype == np.uint8 and p.shape == (32, 32, 3) for p in shown)


def test_the_outlook_modules_import_no_gl():
    import subprocess
    import sys

    code = ("import sys, raytrace.outlook.path.pathtrace, raytrace.outlook.radiosity, "
            "raytrace.outlook.direct, "
            "shadowvol.cli.raytrace.radiosity, shadowvol.course.ladder, raytrace.outlook.photon; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('moderngl', 'OpenGL', 'glcontext')]; "
            "print(bad); sys.exit(1 if bad else 0)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
