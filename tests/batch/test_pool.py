"""The local pool: each worker's own contiguous lane of frames, taking over the far end of the
others' when its own is done; the thread settings of a worker; a worker killed mid-run fails
only the frames it held and the others make the rest; a scene the parent cannot load fails in
the workers as it does in one process; workers whose parent was killed end on their own."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from collections import deque
from pathlib import Path

import pytest
from builders import ROOT, job_lines, write_jobs

from shadowvol import batch
from shadowvol.batch import job_frames, local
from shadowvol.batch.jobs import check_jobs
from shadowvol.batch.worker import THREAD_VARIABLES, thread_settings
from shadowvol.cli import status


def test_lanes_are_contiguous_and_a_finished_worker_takes_the_far_end_of_the_longest():
    tasks = [[{"id": i}] for i in range(10)]
    runs = local.lanes(tasks, 3)
    assert [[t[0]["id"] for t in run] for run in runs] == [[0, 1, 2], [3, 4, 5], [6, 7, 8, 9]]
    order = [local.next_task(runs, 0)[0]["id"] for _ in range(3)]
    assert order == [0, 1, 2]
    assert local.next_task(runs, 0)[0]["id"] == 9   # lane 2 is the longest: its far end
    assert local.next_task(runs, 0)[0]["id"] == 5   # now lanes 1 and 2 tie: the first
    assert local.next_task(runs, 2)[0]["id"] == 6   # its own lane first
    runs = [deque(), deque()]
    assert local.next_task(runs, 1) is None


def test_thread_settings(monkeypatch):
    for name in THREAD_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    # a share of one core: llvmpipe draws on the calling thread, no rasterizer thread
    assert thread_settings(2, cores=2) == {"LP_NUM_THREADS": "0", "OMP_NUM_THREADS": "1",
                                           "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    assert thread_settings(4, cores=2)["LP_NUM_THREADS"] == "0"
    assert set(thread_settings(2, cores=8).values()) == {"4"}
    monkeypatch.setenv("LP_NUM_THREADS", "3")   # the user's setting is theirs
    assert "LP_NUM_THREADS" not in thread_settings(2, cores=2)


def _specs(count: int):
    job = check_jobs(job_lines(frames=count, size=(32, 24), raytrace=False))[0]
    return list(job_frames.specs(job, job.scene)), {job.scene: job.scene}


@pytest.mark.gl
def test_a_killed_worker_fails_only_the_frames_it_held():
    specs, scenes = _specs(8)
    tasks = local.chunks(specs, 2)
    assert len(tasks) == 8   # one frame a task: lanes of 4
    results, victim = [], None
    for result in local.pool(tasks, scenes, workers=2):
        results.append(result)
        if victim is None and "error" not in result:
            victim = int(re.search(r"pid (\d+)", result["worker"]).group(1))
            os.kill(victim, signal.SIGKILL)
    assert sorted(r["id"] for r in results) == [s.id for s in specs]
    failed = [r for r in results if "error" in r]
    assert 1 <= len(failed) <= local.IN_FLIGHT, failed
    assert all(r["status"] == status.RENDER_FAILED and "worker process died" in r["error"]
               for r in failed)
    made_by = {r["id"]: r["worker"] for r in results if "error" not in r}
    survivor = {w for w in made_by.values() if f"pid {victim})" not in w}
    assert len(survivor) == 1 and len(made_by) == 8 - len(failed)


@pytest.mark.gl
def test_a_scene_that_does_not_load_fails_in_the_pool_as_in_one_process(tmp_path):
    good = job_lines(frames=2, size=(32, 24), raytrace=False)[0]
    missing = dict(good, name="missing-mesh", scene=str(tmp_path / "broken.toml"))
    (tmp_path / "broken.toml").write_text(
        '[camera]\neye = [0.0, 1.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n\n'
        '[[lights]]\ntype = "point"\nposition = [0.0, 3.0, 0.0]\n\n'
        '[[objects]]\nname = "gone"\ntype = "mesh"\npath = "nope.obj"\n')
    jobs = write_jobs(tmp_path / "jobs.jsonl", [missing, good])
    runs = {w: batch.run(jobs, tmp_path / f"out{w}", workers=w, progress=False) for w in (1, 2)}
    for summary in runs.values():
        assert (summary.rendered, summary.failed, summary.status) == (2, 2, status.BAD_INPUT)
    assert runs[1].errors == runs[2].errors and "nope.obj" in runs[1].errors[0]


def _alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except (FileNotFoundError, IndexError):
        return False


@pytest.mark.gl
def test_workers_end_when_their_parent_is_killed(tmp_path):
    jobs = write_jobs(tmp_path / "jobs.jsonl", job_lines(frames=16, size=(64, 48),
                                                         raytrace=False))
    manifest = tmp_path / "out" / "manifest.jsonl"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]))
    run = subprocess.Popen([sys.executable, "-m", "shadowvol", "batch", str(jobs), "-o",
                            str(tmp_path / "out"), "--workers", "2"], env=env,
                           stderr=subprocess.DEVNULL)
    pids: set[int] = set()
    deadline = time.monotonic() + 120
    while len(pids) < 2 and run.poll() is None:   # both workers have sent frames
        assert time.monotonic() < deadline, "the workers made no frames in 120 s"
        if manifest.exists():
            for line in manifest.read_text().splitlines():
                if line.startswith('{"id"') and line.endswith("}"):
                    pids.add(int(re.search(r"pid (\d+)", json.loads(line)["worker"]).group(1)))
        time.sleep(0.005)
    assert run.poll() is None, "the run ended before both workers were seen: make it longer"
    os.kill(run.pid, signal.SIGKILL)   # the parent alone: nothing tells the workers
    run.wait()
    deadline = time.monotonic() + 60
    while any(_alive(pid) for pid in pids):
        assert time.monotonic() < deadline, f"workers {pids} outlived their parent by 60 s"
        time.sleep(0.05)


@pytest.mark.gl
@pytest.mark.parametrize("signum, raised", [(signal.SIGINT, KeyboardInterrupt),
                                            (signal.SIGTERM, "Terminated")])
def test_a_signal_while_the_workers_start_leaves_none_behind(monkeypatch, capfd, signum, raised):
    """A signal that lands while the pool starts its second worker: both started workers are
    ended, and neither prints a traceback (one left behind died reading its start-up data from
    the parent's closed pipe: 'EOFError: Ran out of input', seen under the signal stress of
    benchmarks/stress_signals.py)."""
    from multiprocessing.context import SpawnProcess

    from shadowvol import signals

    started = []
    real_start = SpawnProcess.start

    def start(self):
        real_start(self)
        started.append(self)
        if len(started) == 2:
            os.kill(os.getpid(), signum)  # mid-start: the child exists, the parent is cut

    monkeypatch.setattr(SpawnProcess, "start", start)
    tasks = [[{"id": f"j/{i:06d}", "scene": "s"}] for i in range(4)]
    expected = signals.Terminated if raised == "Terminated" else raised
    with signals.handled():
        with pytest.raises(expected):
            next(local.pool(tasks, {"s": str(ROOT / "scenes" / "cage.toml")}, workers=2))
    assert len(started) == 2
    for process in started:
        process.join(10)
        assert not process.is_alive(), "a worker was left behind"
    time.sleep(0.5)
    assert "Traceback" not in capfd.readouterr().err


def test_a_pool_worker_answers_ctrl_c_with_the_handler_that_waits_for_a_safe_line():
    """A Ctrl-C in a terminal reaches the pool's workers too.  They had Python's own SIGINT
    handler, which raises KeyboardInterrupt inside moderngl's callbacks as well: the SIGSEGV
    of docs/robustness.md ("Signals at random moments").  `_serve` installs `signals`' handler,
    which answers a signal there 10 ms later (tests/cli/test_signals.py)."""
    import queue

    from shadowvol import signals

    tasks = queue.Queue()
    tasks.put(None)  # no work: the worker starts, installs its handlers, and ends
    previous = signal.getsignal(signal.SIGINT)
    try:
        local._serve(tasks, None, None, {}, "a test's worker")
        assert signal.getsignal(signal.SIGINT) is signals._handler
    finally:
        signal.signal(signal.SIGINT, previous)
