"""A FIFO, a device or a directory named as a job file, a job's scene or a mesh a glTF names is
refused before a byte of it is read (issue 36, step 4): exit 2 and one line naming the file,
never a hang.  Each run is a subprocess with a timeout, so a regression fails, not hangs.
Nothing here needs GL: no frame is rendered."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from builders import ROOT, SCENES

from shadowvol.cli import status

TIMEOUT = 60
ORBIT = {"orbit": {"center": [0, 1, 0], "radius": 6, "frames": 1}}


def batch(tmp_path, jobs) -> subprocess.CompletedProcess:
    try:
        return subprocess.run([sys.executable, "-m", "shadowvol", "batch", str(jobs), "-o",
                               str(tmp_path / "out"), "--no-progress"], cwd=ROOT,
                              capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        pytest.fail(f"shadowvol batch {jobs.name} hung (still running after {TIMEOUT} s)")


def special(tmp_path, kind: str, name: str):
    """A FIFO, /dev/zero (through a link) or a directory at tmp_path/name."""
    path = tmp_path / name
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "zero":
        path.symlink_to("/dev/zero")
    else:
        path.mkdir()
    return path


WHAT = {"fifo": "is a FIFO (named pipe), not a regular file: not read",
        "zero": "is a character device, not a regular file: not read",
        "dir": "is a directory, not a regular file: not read"}


@pytest.mark.parametrize("kind", ["fifo", "zero", "dir"])
def test_a_job_file_that_is_not_a_regular_file_is_refused_unread(tmp_path, kind):
    jobs = special(tmp_path, kind, "jobs.jsonl")
    done = batch(tmp_path, jobs)
    assert done.returncode == status.BAD_INPUT, done.stderr
    assert done.stderr.strip() == f"error: {jobs}: the job file {WHAT[kind]}", done.stderr


@pytest.mark.parametrize("kind", ["fifo", "zero", "dir"])
def test_a_job_whose_scene_is_not_a_regular_file_is_a_bad_job(tmp_path, kind):
    scene = special(tmp_path, kind, "s.json")
    good = {"name": "good", "scene": str(SCENES / "cage.toml"), "cameras": ORBIT,
            "size": [8, 6], "outputs": ["masks"], "renderer": "raytrace", "max_depth": 0}
    jobs = tmp_path / "jobs.jsonl"
    jobs.write_text(json.dumps({"name": "bad", "scene": "s.json", "cameras": ORBIT}) + "\n" +
                    json.dumps(good) + "\n")
    done = batch(tmp_path, jobs)
    assert done.returncode == status.BAD_INPUT, done.stderr
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert errors == [f"error: {jobs}:1: scene: the scene file {scene} {WHAT[kind]}"], \
        done.stderr
    records = [json.loads(line) for line in (tmp_path / "out" / "manifest.jsonl").open()]
    assert [r["id"] for r in records] == ["job/bad", "good/000000"]
    assert "error" not in records[1]  # the other job is made


def test_a_gltf_buffer_that_is_a_fifo_is_refused_unread(tmp_path):
    os.mkfifo(tmp_path / "buf.bin")
    gltf = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "max": [1, 1, 0], "min": [0, 0, 0]}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}],
            "buffers": [{"byteLength": 36, "uri": "buf.bin"}]}
    (tmp_path / "m.gltf").write_text(json.dumps(gltf))
    scene = tmp_path / "s.json"
    scene.write_text(json.dumps({"camera": {"eye": [0, 1, 3], "target": [0, 0, 0]},
                                 "objects": [{"type": "mesh", "path": "m.gltf"}]}))
    try:
        done = subprocess.run([sys.executable, "-c", "import sys; from shadowvol.scenefile "
                               "import load_scene; load_scene(sys.argv[1])", str(scene)],
                              cwd=ROOT, capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        pytest.fail("load_scene hung on a glTF whose buffer is a FIFO")
    assert "SceneError" in done.stderr and "Traceback" in done.stderr  # raised, not a hang
    line = done.stderr.strip().splitlines()[-1]
    assert f"{scene}: objects[0].path: {tmp_path / 'm.gltf'}: the file it names 'buf.bin' " \
           f"{WHAT['fifo']}" in line, line
