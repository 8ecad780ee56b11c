"""The bad-input sweep: each case once gave a traceback, a misleading message or a lost file.
Every one must now end with one clear line on stderr, the documented exit status, no traceback,
and no output file written or changed."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from builders import ROOT, SCENES

pytestmark = pytest.mark.gl

BAD_INPUT = 2


def run(args: list[str], cwd) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT),
                                                       os.environ.get("PYTHONPATH", "")]))
    return subprocess.run([sys.executable, "-m", *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=300)


def refused(done: subprocess.CompletedProcess, *words: str) -> str:
    """One `error:` line naming `words`, exit 2, no traceback."""
    lines = done.stderr.strip().splitlines()
    assert done.returncode == BAD_INPUT, done.stderr
    assert len(lines) == 1 and lines[0].startswith("error: "), done.stderr
    assert "Traceback" not in done.stderr
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


def files(folder) -> dict[str, bytes | str]:
    return {p.name: (os.readlink(p) if p.is_symlink() else p.read_bytes())
            for p in folder.iterdir()}


@pytest.mark.parametrize("command, flag, name", [
    (["shadowvol", "render", str(SCENES / "cage.toml"), "-o", "loop.png"], "-o", "loop.png"),
    (["shadowvol", "render", str(SCENES / "cage.toml"), "-o", "x.png", "--masks", "loop.npz"],
     "--masks", "loop.npz"),
    (["raytrace", "masks", str(SCENES / "cage.toml"), "-o", "loop.npz"], "-o", "loop.npz"),
])
def test_an_output_that_is_a_loop_of_links(tmp_path, command, flag, name):
    stem, suffix = name.split(".")
    os.symlink(f"{stem}2.{suffix}", tmp_path / name)
    os.symlink(name, tmp_path / f"{stem}2.{suffix}")
    before = files(tmp_path)
    refused(run(command, tmp_path), flag, name, "loop")
    assert files(tmp_path) == before


def test_the_stencil_picture_of_an_area_light(tmp_path):
    refused(run(["shadowvol", "render", str(SCENES / "soft.toml"), "-o", "s.png", "--stencil",
                 "st.png"], tmp_path), "lights[0]", "area light", "--stencil")
    assert list(tmp_path.iterdir()) == []


LONG_NAME = "n" * 300 + ".png"                             # over the 255 bytes a name may have
DEEP = "/".join(["d" * 60] * 80)                            # a 4,900-character path


@pytest.mark.parametrize("command", [
    ["shadowvol", "render", str(SCENES / "cage.toml"), "-o", LONG_NAME],
    ["shadowvol", "render", str(SCENES / "cage.toml"), "-o", f"{DEEP}/x.png"],
    ["raytrace", "masks", str(SCENES / "cage.toml"), "-o", f"{DEEP}/x.npz"],
    ["shadowvol", "render", f"{DEEP}/scene.toml", "-o", "x.png"],
    ["raytrace", "render", f"{DEEP}/scene.toml", "-o", "x.png"],
], ids=["long name", "deep output", "deep masks", "deep scene", "deep scene raytrace"])
def test_a_long_path_is_named_short(tmp_path, command):
    """The message keeps the path's start and its file name, never the whole path."""
    line = refused(run(command, tmp_path))
    path = next(a for a in command if a.startswith(("n" * 10, "d" * 10)))
    name = path.rpartition("/")[2]
    assert len(line) < 250, line
    assert path[:8] in line and (name if len(name) < 60 else name[-8:]) in line, line
    assert "Errno" not in line


def test_each_command_speaks_for_itself(tmp_path):
    line = refused(run(["raytrace", "masks", str(SCENES / "cage.toml"), "-o", "m.png"],
                       tmp_path), "-o", "m.png")
    assert "raytrace writes NPZ" in line and "shadowvol" not in line


@pytest.mark.parametrize("text, key, given", [
    ('{"camera": [1, 2]}', "camera", "got a list"),
    ('{"camera": {"eye": [0, 1, 5], "target": [0, 0, 0]}, "objects": {"a": 1}}', "objects",
     "got a table"),
    ('{"camera": {"eye": [0, 1, 5], "target": [0, 0, 0]}, "lights": "sun"}', "lights",
     "got the string 'sun'"),
])
def test_a_wrong_type_is_named_in_the_files_terms(tmp_path, text, key, given):
    (tmp_path / "s.json").write_text(text)
    line = refused(run(["shadowvol", "render", "s.json", "-o", "x.png"], tmp_path), key, given)
    assert "_Json" not in line and "dict" not in line


@pytest.mark.parametrize("command, words", [
    (["raytrace", "render", str(SCENES / "cornell.toml"), "--integrator", "path", "--seed", "-1",
      "-o", "x.png"], ("--seed", ">= 0", "-1")),
    (["raytrace", "render", str(SCENES / "cornell.toml"), "--integrator", "photon", "--seed",
      "-1", "-o", "x.png"], ("--seed", ">= 0")),
    (["raytrace", "render", str(SCENES / "whitted.toml"), "--seed", "-1", "-o", "x.png"],
     ("--seed", ">= 0")),
    (["shadowvol", "render", str(SCENES / "cage.toml"), "--memory-budget=-5GB", "-o", "x.png"],
     ("--memory-budget", "-5GB")),
], ids=["path seed", "photon seed", "whitted seed", "negative budget"])
def test_a_value_out_of_range(tmp_path, command, words):
    """Once a numpy ValueError traceback (a negative seed) or a message naming the environment
    variable for a flag's value (the budget)."""
    refused(run(command, tmp_path), *words)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("command, words", [
    (["shadowvol", "batch", "--format", "tfrecord", "-o", "out", "jobs.jsonl"],
     ("shadowvol batch: error:", "--format", "tfrecord", "shadowvol batch --help")),
    (["shadowvol", "render", str(SCENES / "cage.toml"), "--memory-budget", "-5GB", "-o", "x.png"],
     ("shadowvol render: error:", "--memory-budget")),
    (["raytrace", "render", "--spp", "many", "x.toml", "-o", "x.png"],
     ("raytrace render: error:", "--spp", "many")),
    (["shadowvol"], ("shadowvol: error:", "COMMAND")),
], ids=["batch format", "budget as a flag", "spp", "no command"])
def test_a_usage_error_is_one_line(tmp_path, command, words):
    """argparse's mistakes are one line too (the usage block is --help's), exit 2."""
    done = run(command, tmp_path)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == BAD_INPUT and len(lines) == 1, done.stderr
    for word in words:
        assert word in lines[0], lines[0]
    assert list(tmp_path.iterdir()) == []
