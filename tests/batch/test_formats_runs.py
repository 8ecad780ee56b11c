"""The dataset layouts (`--format nerfstudio|bop|coco|istd|soba|soba-lights`) are made like the other formats: a run
killed with SIGKILL and rerun, N shards, a process pool and Ray all end with the bytes of one
uninterrupted run, index files included."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest
from builders import ROOT, job_lines, output_files, write_jobs

from shadowvol import batch
from shadowvol.batch.layouts import DATASETS as NAMES

pytestmark = pytest.mark.gl

FRAMES = 8          # of the turntable; the traced job adds 2
ALL = FRAMES + 2


@pytest.fixture(scope="module")
def jobs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("jobs")
    return write_jobs(folder / "jobs.jsonl", job_lines(frames=FRAMES, size=(64, 48)))


@pytest.fixture(scope="module")
def references(jobs, tmp_path_factory):
    made = {}

    def reference(format: str):
        if format not in made:
            out = tmp_path_factory.mktemp(f"reference-{format}") / "out"
            summary = batch.run(jobs, out, format=format, progress=False)
            assert (summary.status, summary.rendered) == (0, ALL), summary.errors
            made[format] = out
        return made[format]
    return reference


def _frame_lines(path) -> int:
    try:
        return sum(1 for line in path.read_bytes().split(b"\n") if line.startswith(b'{"id"'))
    except FileNotFoundError:
        return 0


@pytest.mark.parametrize("format", NAMES)
def test_sigkill_then_rerun_gives_the_same_files(jobs, references, tmp_path, compare_outputs,
                                                 format):
    ref = references(format)
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]))
    run = subprocess.Popen([sys.executable, "-m", "shadowvol", "batch", str(jobs), "-o",
                            str(out), "--format", format], env=env, start_new_session=True,
                           stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    while _frame_lines(out / "manifest.jsonl") < 2 and run.poll() is None:
        assert time.monotonic() < deadline, "the run made no frames in 120 s"
        time.sleep(0.005)
    os.killpg(run.pid, signal.SIGKILL)
    run.wait()
    made = _frame_lines(out / "manifest.jsonl")
    assert run.returncode == -signal.SIGKILL and made < ALL, \
        f"the run ended before the kill ({made} of {ALL} frames): make it longer"

    summary = batch.run(jobs, out, format=format, progress=False)
    assert summary.status == 0, summary.errors
    assert summary.rendered + summary.skipped == ALL and summary.skipped >= 1
    compare_outputs(out, ref)   # index files too: rebuilt, not appended


@pytest.mark.parametrize("format", NAMES)
def test_shards_make_the_dataset_of_one_run(jobs, references, tmp_path, compare_outputs,
                                            format):
    ref, out = references(format), tmp_path / "out"
    for index in range(2):
        summary = batch.run(jobs, out, shard=(index, 2), format=format, progress=False)
        assert summary.status == 0, summary.errors
    got, want = output_files(out), output_files(ref)
    assert sorted(got) == sorted(want)
    assert [k for k in want if got[k] != want[k]] == []  # the last shard's index has them all
    again = batch.run(jobs, out, format=format, progress=False)
    assert (again.status, again.rendered, again.skipped) == (0, 0, ALL)
    compare_outputs(out, ref)


@pytest.mark.parametrize("format", NAMES)
def test_a_process_pool_makes_the_same_files(jobs, references, tmp_path, compare_outputs,
                                             format):
    summary = batch.run(jobs, tmp_path / "out", workers=2, format=format, progress=False)
    assert (summary.status, summary.rendered) == (0, ALL), summary.errors
    compare_outputs(tmp_path / "out", references(format))


@pytest.mark.parametrize("format", NAMES)
def test_ray_makes_the_same_files(jobs, references, tmp_path, compare_outputs, ray_session,
                                  format):
    summary = batch.run(jobs, tmp_path / "out", workers=2, ray=True, format=format,
                        progress=False)
    assert (summary.status, summary.rendered) == (0, ALL), summary.errors
    compare_outputs(tmp_path / "out", references(format))


def test_a_frame_of_one_layout_is_not_taken_for_another_s(jobs, tmp_path):
    out = tmp_path / "out"
    assert batch.run(jobs, out, format="coco", progress=False).rendered == ALL
    again = batch.run(jobs, out, format="nerfstudio", progress=False)  # another spec hash
    assert (again.status, again.rendered) == (0, ALL)


@pytest.mark.parametrize("format", NAMES)
def test_a_failed_frame_is_left_out_of_the_index(tmp_path, format):
    lines = job_lines(frames=2, size=(32, 24), raytrace=False)
    lines.append({"name": "lost", "scene": str(tmp_path / "no-such-scene.toml"),
                  "cameras": [{"eye": [4.2, 3.4, 5.2], "target": [-0.6, 1.0, -0.8]}]})
    jobs = write_jobs(tmp_path / "jobs.jsonl", lines)
    summary = batch.run(jobs, tmp_path / "out", format=format, progress=False)
    assert (summary.status, summary.rendered, summary.failed) == (2, 2, 1)
    # the index of each job: nerfstudio's and COCO's in its folder, BOP's in its scene folder
    # (the job's place in the job file)
    made, lost = ({"nerfstudio": f"{job}/transforms.json", "bop": f"train/{place}/scene_gt.json",
                   "coco": f"{job}/annotations.json", "istd": f"{job}/istd.json",
                   "soba": f"{job}/annotations.json",
                   "soba-lights": f"{job}/annotations.json"}[format]
                  for job, place in (("cage-turntable", "000000"), ("lost", "000001")))
    made = json.loads((tmp_path / "out" / made).read_text())
    lost = json.loads((tmp_path / "out" / lost).read_text())
    count = {"nerfstudio": lambda d: len(d["frames"]), "bop": len,
             "coco": lambda d: len(d["images"]), "istd": lambda d: len(d["frames"]),
             "soba": lambda d: len(d["images"]), "soba-lights": lambda d: len(d["images"])}[format]
    assert (count(made), count(lost)) == (2, 0)
