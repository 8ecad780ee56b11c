"""The `raytrace` command end to end: render, masks (+ their picture), --help, and bad input
giving a clear message and exit status 2 (no traceback)."""

import os
import subprocess
import sys

import numpy as np
import pytest
from builders import ROOT
from PIL import Image

import raytrace
from shadowvol.cli.raytrace import main
from shadowvol.io import encode_srgb, load_masks
from shadowvol.scenefile import load_scene

SMALL = """
name = "small"
[image]
width = 48
height = 36
[camera]
eye = [0.0, 2.0, 5.0]
target = [0.0, 0.5, 0.0]
[[lights]]
type = "point"
position = [2.0, 5.0, 2.0]
[[lights]]
type = "directional"
direction = [-0.3, -1.0, 0.2]
[[objects]]
type = "plane"
size = [6.0, 6.0]
[[objects]]
type = "sphere"
center = [0.0, 0.8, 0.0]
radius = 0.6
material = { reflectivity = 0.5 }
[[objects]]
type = "box"
center = [1.2, 0.3, 0.5]
size = [0.6, 0.6, 0.6]
"""


@pytest.fixture
def small(tmp_path):
    path = tmp_path / "small.toml"
    path.write_text(SMALL)
    return path


def test_render(small, tmp_path, capsys):
    out = tmp_path / "out" / "small.png"
    assert main(["render", str(small), "-o", str(out), "--max-depth", "2"]) == 0
    written = np.asarray(Image.open(out))
    expect = encode_srgb(raytrace.render(load_scene(small), max_depth=2))
    assert written.shape == (36, 48, 3) and np.array_equal(written, expect)
    assert "wrote" in capsys.readouterr().err


def test_masks_npz_and_picture(small, tmp_path):
    out = tmp_path / "m.npz"
    assert main(["masks", str(small), "-o", str(out), "--backend", "numpy"]) == 0
    lit, coverage = load_masks(out)
    ref_lit, ref_cov = raytrace.shadow_masks(load_scene(small), backend="numpy")
    assert lit.shape == (2, 36, 48) and lit.dtype == bool
    assert np.array_equal(lit, ref_lit) and np.array_equal(coverage, ref_cov)
    picture = np.asarray(Image.open(tmp_path / "m.png"))  # by default beside the npz
    assert picture.shape == (36, 2 * 48 + 4, 3)
    other = tmp_path / "pics" / "masks.png"
    assert main(["masks", str(small), "-o", str(tmp_path / "n.npz"), "--png", str(other)]) == 0
    assert other.is_file() and not (tmp_path / "n.png").exists()
    assert main(["masks", str(small), "-o", str(tmp_path / "q.npz"), "--no-png"]) == 0
    assert not (tmp_path / "q.png").exists()


def test_masks_and_picture_may_not_share_a_name(small, tmp_path, capsys):
    assert main(["masks", str(small), "-o", str(tmp_path / "m.png")]) == 2
    assert "error:" in capsys.readouterr().err
    assert not (tmp_path / "m.png").exists()


def test_help_explains_every_option(capsys):
    for command, options in [("render", ["--output", "--max-depth", "--backend",
                                         "--no-progress"]),
                             ("masks", ["--output", "--png", "--no-png", "--backend"])]:
        with pytest.raises(SystemExit) as exc:
            main([command, "--help"])
        assert exc.value.code == 0
        text = capsys.readouterr().out
        for option in options:
            assert option in text
        assert "SCENE" in text


BAD = [
    ("[camera]\neye = [0, 0, 0]\ntarget = [0, 0, 0]\n[[objects]]\ntype = 'box'\n",
     "camera.target: eye and target are the same point"),
    ("[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\n[[objects]]\ntype = 'sphere'\n"
     "center = [0, 0, 0]\nradius = -1\n", "radius"),
    ("[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\ncolour = 3\n", "camera.colour: unknown key"),
]


@pytest.mark.parametrize("command", ["render", "masks"])
@pytest.mark.parametrize("text, message", BAD)
def test_bad_scene_exits_2_with_a_clear_message(tmp_path, capsys, command, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    out = tmp_path / ("x.png" if command == "render" else "x.npz")
    assert main([command, str(path), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {path}: ") and message in err
    assert not out.exists()


def test_bad_scene_in_a_real_process(tmp_path):
    """The message names the file and the key, the status is 2, and there is no traceback."""
    path = tmp_path / "bad.toml"
    path.write_text(BAD[0][0])
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.run([sys.executable, "-c", "import sys; from shadowvol.cli.raytrace "
                           "import main; sys.exit(main())", "masks", str(path), "-o",
                           str(tmp_path / "x.npz")],
                          capture_output=True, text=True, env=env)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr == f"error: {path}: {BAD[0][1]}\n"
    assert not (tmp_path / "x.npz").exists()


def test_missing_scene_file(tmp_path, capsys):
    assert main(["render", str(tmp_path / "nope.toml"), "-o", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "nope.toml" in err
