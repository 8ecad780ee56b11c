"""Datasets made of links (DVC, git-annex) and jittered area lights: a rerun never writes
through a link into another output, and jitter moves an area light whole."""

from __future__ import annotations

import os

import numpy as np
import pytest
from builders import SCENES, job_lines, write_jobs

from shadowvol import batch
from shadowvol.batch import job_frames
from shadowvol.scene import AreaLight, Camera, PointLight

pytestmark = pytest.mark.gl


def test_a_rerun_replaces_a_link_and_leaves_what_it_pointed_to(tmp_path):
    jobs = write_jobs(tmp_path / "jobs.jsonl", job_lines(frames=3, raytrace=False))
    out = tmp_path / "out"
    assert batch.run(jobs, out, progress=False).rendered == 3
    folder = out / "cage-turntable"
    made = {p.name: p.read_bytes() for p in folder.iterdir()}
    # frame 0's image becomes a link to frame 1's, as a deduplicating dataset tool makes them
    (folder / "000000.png").unlink()
    os.symlink("000001.png", folder / "000000.png")

    again = batch.run(jobs, out, progress=False)
    assert (again.status, again.rendered, again.skipped) == (0, 1, 2)
    assert not (folder / "000000.png").is_symlink()
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == made   # frame 1 untouched
    steady = batch.run(jobs, out, progress=False)
    assert (steady.status, steady.rendered, steady.skipped) == (0, 0, 3)


def test_a_link_to_the_right_bytes_is_already_made(tmp_path):
    """A content-addressed link (the same bytes elsewhere) is a made frame: left as it is."""
    jobs = write_jobs(tmp_path / "jobs.jsonl", job_lines(frames=2, raytrace=False))
    out = tmp_path / "out"
    assert batch.run(jobs, out, progress=False).rendered == 2
    frame = out / "cage-turntable" / "000000.png"
    store = tmp_path / "cache" / "ab12"
    store.parent.mkdir()
    store.write_bytes(frame.read_bytes())
    frame.unlink()
    os.symlink(store, frame)
    again = batch.run(jobs, out, progress=False)
    assert (again.status, again.rendered, again.skipped) == (0, 0, 2)
    assert frame.is_symlink()


def test_jitter_moves_an_area_light_whole():
    camera = Camera(eye=[0, 1, 5], target=[0, 0, 0])
    area = AreaLight("rect", center=[0, 3, 0], normal=[0, -1, 0], size=[1.0, 0.5], samples=9)
    lights = (PointLight([1, 3, 0]), area)
    _, (point, moved) = job_frames.jittered(camera, lights, {"lights": 0.3}, 5, 2)
    offset = moved.center - area.center
    assert 0 < np.linalg.norm(offset) <= 0.3
    np.testing.assert_allclose(moved.positions, area.positions + offset, rtol=0, atol=1e-12)
    assert (moved.shape, moved.samples, moved.size.tolist()) == ("rect", 9, [1.0, 0.5])
    assert not np.array_equal(point.position, lights[0].position)


def test_a_jittered_job_with_an_area_light_renders(tmp_path):
    job = {"name": "soft", "scene": str(SCENES / "soft.toml"), "size": [32, 24],
           "cameras": [{"eye": [0.0, 4.0, 6.0], "target": [0.0, 0.0, 0.0]}] * 2,
           "jitter": {"eye": 0.1, "lights": 0.2}, "outputs": ["image", "masks"]}
    summary = batch.run(write_jobs(tmp_path / "jobs.jsonl", [job]), tmp_path / "out",
                        progress=False)
    assert (summary.status, summary.rendered, summary.failed) == (0, 2, 0), summary.errors
