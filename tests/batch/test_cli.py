"""`shadowvol batch` as a user runs it: the help's exit-status table, device selection, the
Ray extra named when missing, Ray actors that die mid-run."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest
from builders import ROOT, job_lines, write_jobs

from shadowvol import batch
from shadowvol.cli import status
from shadowvol.cli.main import main
from shadowvol.raster.platform.egl import devices


def test_help_prints_the_exit_status_table(capsys):
    with pytest.raises(SystemExit):
        main(["batch", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert " ".join(status.EPILOG.split()) in text and "--egl-device" in text


@pytest.mark.gl
def test_an_egl_device_by_index_and_a_bad_one(tmp_path, capsys):
    jobs = write_jobs(tmp_path / "jobs.jsonl", job_lines(frames=1, size=(16, 12),
                                                         raytrace=False))
    found = devices()
    assert found, "EGL lists no device here"
    assert main(["batch", str(jobs), "-o", str(tmp_path / "out"), "--egl-device", "0"]) == 0
    record = json.loads((tmp_path / "out" / "manifest.jsonl").read_text())
    assert record["device"].startswith("EGL device 0")
    assert "renders on EGL device 0" in capsys.readouterr().err  # the choice is logged
    bad = str(len(found))
    assert main(["batch", str(jobs), "-o", str(tmp_path / "o2"), "--egl-device", bad]) == \
        status.BAD_INPUT
    err = capsys.readouterr().err
    assert f"no EGL device {bad}; this machine has {len(found)}: 0 (" in err
    assert len(err.strip().splitlines()) == 1
    assert main(["batch", str(jobs), "-o", str(tmp_path / "o3"), "--egl-device", "auto"]) == 0


def test_ray_missing_is_bad_input_naming_the_extra(tmp_path):
    jobs = write_jobs(tmp_path / "jobs.jsonl", job_lines(frames=1, raytrace=False))
    code = textwrap.dedent(f"""
        import sys
        class Block:
            def find_spec(self, name, path=None, target=None):
                if name.split(".")[0] == "ray":
                    raise ImportError("blocked for the test", name=name)
        sys.meta_path.insert(0, Block())
        from shadowvol.cli.main import main
        sys.exit(main(["batch", {str(jobs)!r}, "-o", {str(tmp_path / "out")!r}, "--ray"]))
        """)
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == status.BAD_INPUT, done.stderr
    assert "pip install 'shadowvol[ray]'" in done.stderr and "Traceback" not in done.stderr


def _actor_pids() -> list[int]:
    pids = []
    for proc in Path("/proc").iterdir():
        try:
            if proc.name.isdigit() and (proc / "cmdline").read_bytes().startswith(
                    b"ray::FrameActor"):
                pids.append(int(proc.name))
        except OSError:
            pass
    return pids


@pytest.mark.gl
def test_a_dead_ray_actor_has_its_frames_made_elsewhere(tmp_path, compare_outputs,
                                                         ray_session):
    jobs = write_jobs(tmp_path / "jobs.jsonl", job_lines(frames=12, size=(48, 36),
                                                         raytrace=False))
    assert batch.run(jobs, tmp_path / "ref", progress=False).status == 0
    killed = []

    def kill_one():  # once the first frames are in, SIGKILL one actor's process
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not killed:
            text = (tmp_path / "out" / "manifest.jsonl")
            pids = _actor_pids()
            if text.exists() and text.read_text().count("\n") >= 2 and pids:
                os.kill(pids[0], signal.SIGKILL)
                killed.append((pids[0], pids))
            time.sleep(0.01)

    killer = threading.Thread(target=kill_one)
    killer.start()
    summary = batch.run(jobs, tmp_path / "out", workers=2, ray=True, progress=False)
    killer.join()
    assert killed, "no actor was killed"
    assert summary.status == 0 and summary.rendered == 12, summary.errors
    compare_outputs(tmp_path / "out", tmp_path / "ref")
    # the killed actor was one of this run's two, and held tasks (each actor has two in flight
    # while frames are queued): the run could only end complete by making them elsewhere
    assert len(killed[0][1]) == 2, killed
