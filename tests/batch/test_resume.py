"""Nothing lost: a run killed with SIGKILL (the whole process group, workers too) at some point,
then rerun, ends with exactly the files of an uninterrupted run; a rerun remakes only what is
missing, damaged or changed."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest
from builders import ROOT, job_lines, write_jobs

from shadowvol import batch

pytestmark = pytest.mark.gl

FRAMES = 16


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    folder = tmp_path_factory.mktemp("reference")
    jobs = write_jobs(folder / "jobs.jsonl", job_lines(frames=FRAMES, size=(64, 48),
                                                       raytrace=False))
    summary = batch.run(jobs, folder / "out", progress=False)
    assert summary.status == 0 and summary.rendered == FRAMES
    return jobs, folder / "out"


def _frame_lines(path) -> int:
    try:
        return sum(1 for line in path.read_bytes().split(b"\n") if line.startswith(b'{"id"'))
    except FileNotFoundError:
        return 0


@pytest.mark.parametrize("workers, kill_after", [(1, 2), (2, 7)])
def test_sigkill_then_rerun_gives_the_same_files(reference, tmp_path, compare_outputs,
                                                 workers, kill_after):
    jobs, ref = reference
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]))
    run = subprocess.Popen([sys.executable, "-m", "shadowvol", "batch", str(jobs), "-o",
                            str(out), "--workers", str(workers)], env=env,
                           start_new_session=True, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    while _frame_lines(out / "manifest.jsonl") < kill_after and run.poll() is None:
        assert time.monotonic() < deadline, "the run made no frames in 120 s"
        time.sleep(0.005)
    os.killpg(run.pid, signal.SIGKILL)  # the parent and its workers, mid-run
    run.wait()
    made = _frame_lines(out / "manifest.jsonl")
    assert run.returncode == -signal.SIGKILL and made < FRAMES, \
        f"the run ended before the kill ({made} of {FRAMES} frames): make it longer"

    summary = batch.run(jobs, out, progress=False)
    assert summary.status == 0, summary.errors
    assert summary.rendered + summary.skipped == FRAMES and summary.skipped >= kill_after - 1
    compare_outputs(out, ref)  # no temporary files, no half files, the same manifest hashes
    assert len((out / "manifest.jsonl").read_text().splitlines()) == FRAMES


def test_rerun_remakes_only_what_is_missing_damaged_or_changed(reference, tmp_path,
                                                               compare_outputs):
    jobs, ref = reference
    out = tmp_path / "out"
    assert batch.run(jobs, out, progress=False).rendered == FRAMES
    (out / "cage-turntable" / "000003.png").write_bytes(b"not a png")
    (out / "cage-turntable" / "000005.masks.npz").unlink()
    (out / "cage-turntable" / ".000007.png.abcd1234.part").write_bytes(b"half")  # a killed write
    again = batch.run(jobs, out, progress=False)
    assert (again.rendered, again.skipped, again.status) == (2, FRAMES - 2, 0)
    compare_outputs(out, ref)

    # a changed job (another radius) changes every frame's spec: all are made again
    lines = [json.loads(line) for line in jobs.read_text().splitlines()]
    lines[0]["cameras"]["orbit"]["radius"] = 7.5
    changed = write_jobs(tmp_path / "changed.jsonl", lines)
    assert batch.run(changed, out, progress=False).rendered == FRAMES


def test_a_second_run_into_the_same_manifest_is_refused(tmp_path):
    from shadowvol.batch import manifest
    from shadowvol.errors import InputError

    jobs = write_jobs(tmp_path / "jobs.jsonl", job_lines(frames=1, raytrace=False))
    held = manifest.Journal(tmp_path / "out" / "manifest.jsonl")  # as a running batch holds it
    try:
        with pytest.raises(InputError, match="another run is writing"):
            batch.run(jobs, tmp_path / "out", progress=False)
        other = batch.run(jobs, tmp_path / "out", shard=(1, 2), progress=False)  # its own file
        assert (other.status, other.rendered) == (0, 1)
    finally:
        held.close()
    after = batch.run(jobs, tmp_path / "out", progress=False)
    assert (after.status, after.skipped) == (0, 1)
