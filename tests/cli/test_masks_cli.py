"""`shadowvol masks` end to end, in processes of their own as a user runs it: the masks alone
by the renderer `--renderer` names or, under auto (the default), the one the cost model of
`shadowvol.compare.fastest` takes, said in the log line; auto without a GL takes the ray
tracer; bad input is one line and exit status 2 (3 where a named rasterizer has no GL), and
writes nothing."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
from builders import ROOT, SCENES

from shadowvol.cli import main
from shadowvol.io import load_masks

NO_EGL = {"__EGL_VENDOR_LIBRARY_FILENAMES": "/nonexistent.json"}
SAID = {"shadowvol": "by the rasterizer's mask-only frame", "raytrace": "by the ray tracer"}


def masks(tmp_path, *args: str, env: dict | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "shadowvol", "masks", *args], cwd=tmp_path,
                          capture_output=True, text=True, timeout=300,
                          env={**os.environ, "PYTHONPATH": str(ROOT), **(env or {})})


def test_the_command_is_listed():
    assert "masks" in main.build_parser().format_help()


@pytest.mark.parametrize("args, says", [
    (["--renderer", "rays"], "argument --renderer: invalid choice: 'rays' (choose from 'auto', "
                             "'shadowvol', 'raytrace')"),
    (["--renderer"], "argument --renderer: expected one argument"),
    (["-o", "m.png"], "error: -o: 'm.png' must end in .npz"),
])
def test_bad_input_is_one_line_and_status_2(tmp_path, args, says):
    full = [str(SCENES / "stack.toml"), *(["-o", "m.npz"] if "-o" not in args else []), *args]
    done = masks(tmp_path, *full)
    assert done.returncode == 2, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and says in done.stderr, done.stderr
    assert "Traceback" not in done.stderr and not list(tmp_path.iterdir())


@pytest.mark.gl
@pytest.mark.parametrize("renderer", ["auto", "shadowvol", "raytrace"])
def test_the_log_line_names_the_renderer_that_made_the_masks(tmp_path, renderer):
    done = masks(tmp_path, str(SCENES / "cage.toml"), "-o", "m.npz", "--png", "m.png",
                 *(["--renderer", renderer] if renderer != "auto" else []))
    assert done.returncode == 0, done.stderr
    line = done.stderr.strip().splitlines()[-1]
    assert line.startswith("wrote m.npz, m.png by "), line
    if renderer == "auto":
        assert "(auto: 990 triangles, 307,200 pixels, 1 hard lights on " in line, line
        assert "ms rasterized" in line and "ms ray traced" in line
    else:
        assert line.endswith(f"{SAID[renderer]} ({renderer}: asked for by name)"), line
    lit, coverage = load_masks(tmp_path / "m.npz")
    assert lit.shape == (1, 480, 640) and coverage.any() and lit.any()
    assert (coverage & ~lit[0]).any()
    assert (tmp_path / "m.png").is_file()


@pytest.mark.gl
def test_auto_and_the_named_renderers_agree_on_the_files_but_tie_pixels(tmp_path):
    for renderer in ("shadowvol", "raytrace"):
        assert masks(tmp_path, str(SCENES / "whitted.toml"), "-o", f"{renderer}.npz",
                     "--renderer", renderer).returncode == 0
    with np.load(tmp_path / "shadowvol.npz") as a, np.load(tmp_path / "raytrace.npz") as b:
        assert a.files == b.files
        for key in a.files:
            if key in ("lit", "coverage"):   # ties only (tests/compare/test_fastest.py)
                assert (a[key] != b[key]).mean() < 1e-4, key
            else:
                np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def test_auto_without_a_gl_takes_the_ray_tracer(tmp_path):
    done = masks(tmp_path, str(SCENES / "stack.toml"), "-o", "m.npz", env=NO_EGL)
    assert done.returncode == 0, done.stderr
    assert done.stderr.strip().splitlines()[-1] == "wrote m.npz by the ray tracer (auto: no GL " \
                                                   "here)"
    lit, coverage = load_masks(tmp_path / "m.npz")
    assert coverage.any() and lit.any()


def test_the_rasterizer_named_without_a_gl_is_one_line_and_status_3(tmp_path):
    done = masks(tmp_path, str(SCENES / "stack.toml"), "-o", "m.npz", "--renderer",
                 "shadowvol", env=NO_EGL)
    assert done.returncode == 3, done.stderr
    assert done.stderr.startswith("error: cannot create a headless EGL context")
    assert len(done.stderr.strip().splitlines()) == 1 and not (tmp_path / "m.npz").exists()
