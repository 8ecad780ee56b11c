"""A bad job or frame is recorded in the manifest with its error, the others go on, and the exit
status says whether every frame was made."""

from __future__ import annotations

import json

import pytest
from builders import SCENES, job_lines, write_jobs

from shadowvol import batch
from shadowvol.cli import status
from shadowvol.cli.main import main

pytestmark = pytest.mark.gl


def test_bad_jobs_among_good_ones(tmp_path, capsys):
    good = job_lines(frames=2, size=(32, 24), raytrace=False)[0]
    missing = dict(good, name="missing-scene", scene=str(tmp_path / "nope.toml"))
    broken = dict(good, name="bad-orbit", cameras={"orbit": {"center": [0, 1, 0],
                                                             "radius": -1, "frames": 2}})
    typo = dict(good, name="typo", camera=good["cameras"])
    last = dict(good, name="after")
    jobs = write_jobs(tmp_path / "jobs.jsonl", [good, missing, broken, typo],
                      extra_lines=("{not json", json.dumps(last)))
    out = tmp_path / "out"
    code = main(["batch", str(jobs), "-o", str(out)])
    assert code == status.BAD_INPUT
    records = {r["id"]: r for r in map(json.loads, (out / "manifest.jsonl").read_text()
                                       .splitlines())}
    for job in ("cage-turntable", "after"):
        for i in range(2):
            record = records[f"{job}/{i:06d}"]
            assert "error" not in record and (out / record["files"]["image"]["path"]).is_file()
    assert "cannot read the scene file" in records["missing-scene/000000"]["error"]
    assert "radius" in records["job/bad-orbit"]["error"]
    assert "camera: unknown key" in records["job/typo"]["error"]
    assert "not valid JSON" in records["job/line-5"]["error"]
    err = capsys.readouterr().err
    assert "3 bad jobs" in err and "6 frames: 4 rendered, 0 already made, 2 failed" in err

    # fixed jobs: the rerun makes only what was missing and succeeds
    (tmp_path / "nope.toml").write_text((SCENES / "cage.toml").read_text().replace(
        "meshes/cage.obj", str(SCENES / "meshes" / "cage.obj")))
    fixed = write_jobs(tmp_path / "jobs.jsonl", [good, missing, last])
    summary = batch.run(fixed, out, progress=False)
    assert (summary.rendered, summary.skipped, summary.status) == (2, 4, status.OK)


def test_a_frame_that_fails_to_render_is_status_3(tmp_path):
    # more than the GL allows per side: the frame fails in the renderer, not in the job
    job = dict(job_lines(frames=1, raytrace=False)[0], size=[1 << 16, 2])
    summary = batch.run([job], tmp_path / "out", progress=False)
    assert summary.failed == 1 and summary.status == status.RENDER_FAILED, summary.errors


def test_arguments_are_checked_before_any_work(tmp_path, capsys):
    jobs = write_jobs(tmp_path / "jobs.jsonl", job_lines(frames=1, raytrace=False))
    for argv, words in ((["--shard", "2/2"], "--shard"), (["--workers", "0"], "--workers"),
                        (["--egl-device", "gpu"], "--egl-device")):
        assert main(["batch", str(jobs), "-o", str(tmp_path / "out"), *argv]) == \
            status.BAD_INPUT
        assert words in capsys.readouterr().err
    assert main(["batch", str(tmp_path / "none.jsonl"), "-o", str(tmp_path / "o")]) == \
        status.BAD_INPUT
