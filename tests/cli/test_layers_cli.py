"""The intrinsic layers on the command line (docs/CONVENTIONS.md, "Intrinsic layers"):
`--outputs` names them for `shadowvol render --masks` and `raytrace masks`, the mask file holds
them as float32 (the ray tracer's bit for bit as `raytrace.outlook.layers` makes them), both
identities hold in the file, and an unknown name is a one-line error, exit 2."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from builders import ROOT
from layers import check_identities

from raytrace.outlook.layers import layers
from shadowvol.frame import LAYERS
from shadowvol.scenefile import load_scene

ALL = ",".join(LAYERS)


def _small(tmp_path):
    path = tmp_path / "soft.toml"
    text = (ROOT / "scenes" / "soft.toml").read_text()
    path.write_text(text.replace("width = 640", "width = 64").replace("height = 480",
                                                                      "height = 48"))
    return path


def _run(*args, cwd):
    return subprocess.run([sys.executable, "-m", *args], cwd=cwd, capture_output=True,
                          text=True, timeout=300, env={"PYTHONPATH": str(ROOT),
                                                       "PATH": "/usr/bin:/bin"})


@pytest.mark.gl
def test_render_writes_the_layers(tmp_path):
    scene_path = _small(tmp_path)
    done = _run("shadowvol", "render", str(scene_path), "-o", "r.png", "--masks", "r.npz",
                "--exr", "r.exr", "--outputs", ALL + ",depth", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    with np.load(tmp_path / "r.npz") as f:
        got = {n: f[n] for n in LAYERS}
        assert "depth" in f.files
    scene = load_scene(scene_path)
    assert got["direct"].shape == (len(scene.lights), 48, 64, 3)
    assert all(v.dtype == np.float32 for v in got.values())
    import OpenEXR
    with OpenEXR.File(str(tmp_path / "r.exr")) as f:   # the image, float32 exactly
        image = f.channels()["RGB"].pixels
    check_identities(got, image, got["shadow_free"])
    # and each layer as an EXR beside the image's, the mask file's arrays exactly
    names = [f"r-{n}.exr" for n in ("albedo", "ambient", "shadow_free")] + [
        f"r-{n}-{i}.exr" for n in ("direct", "direct_shadowed") for i in range(len(scene.lights))]
    for name in names:
        layer, _, light = name[2:-4].partition("-")
        want = got[layer][int(light)] if light else got[layer]
        with OpenEXR.File(str(tmp_path / name)) as f:
            np.testing.assert_array_equal(f.channels()["RGB"].pixels, want, err_msg=name)


def test_raytrace_masks_writes_the_layers(tmp_path):
    scene_path = _small(tmp_path)
    done = _run("raytrace", "masks", str(scene_path), "-o", "t.npz", "--outputs", ALL,
                cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    want = layers(load_scene(scene_path))
    with np.load(tmp_path / "t.npz") as f:
        for n in LAYERS:
            assert f[n].dtype == np.float32 and np.array_equal(f[n], want[n]), n


@pytest.mark.parametrize("program", [("shadowvol", "render"), ("raytrace", "masks")])
def test_an_unknown_layer_is_exit_2(tmp_path, program):
    extra = ("--masks", "m.npz") if program[0] == "shadowvol" else ()
    done = _run(*program, str(_small(tmp_path)), "-o", "x.png" if extra else "x.npz", *extra,
                "--outputs", "albedo,glow", cwd=tmp_path)
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0 and "unknown output 'glow'" in done.stderr
