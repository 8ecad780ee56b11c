"""A bad job or frame is recorded in the manifest with its error, the others go on, and the exit
status says whether every frame was made."""

from __future__ import annotations

import json

import pytest
from builders import SCENES, job_lines, output_files, write_jobs

from shadowvol import batch, memory
from shadowvol.cli import status
from shadowvol.cli.main import main
from shadowvol.raster import estimate
from shadowvol.scenefile import load_scene

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


def _wide_then_ordinary(tmp_path, name: str):
    """A batch (one in-process worker, one GL context) of a 40000x8 frame, then an ordinary
    40x30 one; returns (its summary, its records by id, the ordinary frame's files as a
    batch of that frame alone makes them)."""
    good = job_lines(frames=1, size=(40, 30), raytrace=False)[0]
    jobs = [dict(good, name="wide", size=[40000, 8]), dict(good, name="after")]
    out = tmp_path / name
    summary = batch.run(jobs, out, progress=False)
    records = {r["id"]: r for r in map(json.loads, (out / "manifest.jsonl").read_text()
                                       .splitlines())}
    alone = tmp_path / f"{name}-alone"
    assert batch.run([jobs[1]], alone, progress=False).status == status.OK
    want = {k: v for k, v in output_files(alone).items() if k.startswith("after/")}
    got = {k: v for k, v in output_files(out).items() if k.startswith("after/")}
    assert want and got == want, "the frame after the failed one differs from one made alone"
    return summary, records


def test_a_frame_wider_than_the_gl_is_bad_input_and_the_next_frame_is_made(tmp_path):
    """The renderer refuses a frame wider than this GL allows (status 2, naming the scene file
    and `image`) before allocating anything, in batch as in `shadowvol render`."""
    summary, records = _wide_then_ordinary(tmp_path, "out")
    wide = records["wide/000000"]
    assert wide["status"] == status.BAD_INPUT and summary.status == status.BAD_INPUT
    assert wide["error"].startswith(f"{SCENES / 'cage.toml'}: image: 40000x8 is larger than "
                                    "this GL allows ("), wide["error"]
    assert "error" not in records["after/000000"]


def test_a_frame_the_gl_fails_to_allocate_never_poisons_the_next(tmp_path, monkeypatch):
    """A driver that claims a size it then cannot allocate (the size check passed): that
    frame fails to render (status 3) and leaves no GL error for the next frame to read."""
    monkeypatch.setattr("shadowvol.raster.renderer.check_frame_size",
                        lambda ctx, width, height: None, raising=False)
    summary, records = _wide_then_ordinary(tmp_path, "out")
    wide = records["wide/000000"]
    assert wide["status"] == status.RENDER_FAILED, wide
    assert "could not allocate a 40000x8 frame" in wide["error"]
    assert "error" not in records["after/000000"], records["after/000000"]


def test_arguments_are_checked_before_any_work(tmp_path, capsys):
    jobs = write_jobs(tmp_path / "jobs.jsonl", job_lines(frames=1, raytrace=False))
    for argv, words in ((["--shard", "2/2"], "--shard"), (["--workers", "0"], "--workers"),
                        (["--egl-device", "gpu"], "--egl-device")):
        assert main(["batch", str(jobs), "-o", str(tmp_path / "out"), *argv]) == \
            status.BAD_INPUT
        assert words in capsys.readouterr().err
    assert main(["batch", str(tmp_path / "none.jsonl"), "-o", str(tmp_path / "o")]) == \
        status.BAD_INPUT


def test_a_frame_over_the_memory_budget_is_refused_and_the_others_go_on(tmp_path):
    """`--memory-budget` (shadowvol.memory): a frame whose estimate exceeds its worker's share
    is recorded with the one-line refusal (status 2) before anything is rendered; the frames
    that fit are made.  With two workers each has half the budget."""
    small = job_lines(frames=1, size=(32, 24), raytrace=False)[0]
    big = dict(small, name="big", size=[2000, 1500])
    jobs = write_jobs(tmp_path / "jobs.jsonl", [small, big])
    scene = load_scene(small["scene"]).replace(width=2000, height=1500)
    need = estimate.render(scene, written=("png", "masks")).total + memory.BASE
    fits = estimate.render(scene.replace(width=32, height=24),
                           written=("png", "masks")).total + memory.BASE
    out = tmp_path / "out"      # a budget the small frame fits and the big one does not
    summary = batch.run(jobs, out, progress=False, memory_budget=(fits + need) // 2)
    assert (summary.rendered, summary.failed, summary.status) == (1, 1, status.BAD_INPUT)
    record = [json.loads(line) for line in (out / "manifest.jsonl").read_text().splitlines()
              if "big" in line][0]
    assert "image: 2000x1500 needs about" in record["error"]
    assert "more than the memory budget" in record["error"]
    assert not list(out.glob("big/*.png"))
    # the whole budget is enough for one worker, not for each of two
    one = batch.run([big], tmp_path / "one", progress=False, memory_budget=need * 3 // 2)
    assert one.status == status.OK, one.errors
    two = batch.run([dict(big, cameras={"orbit": {**big["cameras"]["orbit"], "frames": 2}})],
                    tmp_path / "two", workers=2, progress=False, memory_budget=need * 3 // 2)
    assert (two.failed, two.status) == (2, status.BAD_INPUT), two.errors
