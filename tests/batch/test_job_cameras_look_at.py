"""A job's cameras are look-at cameras (docs/datasets.md): intrinsics and camera_to_world are
a scene file's camera keys, and in a job they are refused naming the key (exit status 2), while
a job of look-at cameras renders a scene whose own camera is given by matrices."""

from __future__ import annotations

import json

import numpy as np
import pytest
from builders import SCENES

from shadowvol.cli import status
from shadowvol.cli.main import main

pytestmark = pytest.mark.gl

MATRIX_CAMERA = {"fx": 50.0, "fy": 50.0, "cx": 32.0, "cy": 24.0,
                 "camera_to_world": np.eye(4).tolist()}


def test_a_job_camera_given_by_matrices_is_refused_naming_the_key(tmp_path, capsys):
    good = {"name": "look-at", "scene": str(SCENES / "calibrated.toml"), "size": [32, 24],
            "cameras": [{"eye": [4, 3, 5], "target": [0, 1, 0]}], "outputs": ["image", "masks"]}
    bad = dict(good, name="matrices", cameras=[MATRIX_CAMERA])
    jobs = tmp_path / "jobs.jsonl"
    jobs.write_text("\n".join(json.dumps(j) for j in (good, bad)) + "\n")
    out = tmp_path / "out"
    assert main(["batch", str(jobs), "-o", str(out)]) == status.BAD_INPUT
    records = {r["id"]: r for r in map(json.loads, (out / "manifest.jsonl").read_text()
                                       .splitlines())}
    assert "cameras[0].camera_to_world: unknown key" in records["job/matrices"]["error"]
    frame = records["look-at/000000"]
    assert "error" not in frame and (out / frame["files"]["masks"]["path"]).is_file()
    assert "1 bad job" in capsys.readouterr().err
