"""Ctrl-C and SIGTERM at any moment after the entry point starts: one line, status 130 or 143, never a finished or partial
file after the signal (docs/robustness.md)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest
from builders import SCENES

pytestmark = pytest.mark.gl

DELAYS = (0.0, 0.05, 0.2, 0.5, 1.0, 2.0)  # imports, loading, GL, writing
ENTRY = ("from shadowvol.cli import shadowvol_entry; import sys; "
         "sys.exit(shadowvol_entry(sys.argv[1:]))")


def _wait_for_handlers(proc: subprocess.Popen, timeout: float = 30.0) -> None:
    """Until the child catches SIGTERM (Python does not by default: shadowvol's entry point
    does, first thing), read from /proc/PID/status."""
    end = time.monotonic() + timeout
    while time.monotonic() < end and proc.poll() is None:
        with open(f"/proc/{proc.pid}/status") as f:
            caught = next(int(line.split()[1], 16) for line in f if line.startswith("SigCgt"))
        if caught & (1 << (signal.SIGTERM - 1)):
            return
        time.sleep(0.002)


def _exited(proc: subprocess.Popen) -> bool:
    """The child has exited but is not yet reaped (a zombie: a signal to it does nothing)."""
    try:
        with open(f"/proc/{proc.pid}/status") as f:
            return next(line.split()[1] for line in f if line.startswith("State")) == "Z"
    except (FileNotFoundError, StopIteration):
        return True


@pytest.mark.parametrize("signum, code, word", [(signal.SIGINT, 130, "interrupted"),
                                                 (signal.SIGTERM, 143, "terminated")])
@pytest.mark.parametrize("delay", DELAYS)
def test_a_signal_at_any_moment(tmp_path, signum, code, word, delay):
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-c", ENTRY, "render", str(SCENES / "cage.toml"),
                             "-o", str(out / "x.png"), "--masks", str(out / "x.npz")],
                            stderr=subprocess.PIPE, text=True)
    _wait_for_handlers(proc)  # from the moment the entry point runs (not Python's own start-up)
    time.sleep(delay)
    if proc.poll() is not None or _exited(proc):
        pytest.skip(f"the render finished within {delay} s, before the signal")
    os.kill(proc.pid, signum)
    _, err = proc.communicate(timeout=120)
    left = sorted(p.name for p in out.iterdir()) if out.exists() else []
    assert not [n for n in left if n.endswith(".part")] and "Traceback" not in err
    if err.startswith("wrote "):
        # the signal came after the command's work, while the interpreter shut down: the
        # outputs are complete and the process still does not report success
        assert proc.returncode in (code, -signum) and left == ["x.npz", "x.png"], err
        return
    assert proc.returncode == code, err
    assert err.strip().splitlines()[-1] == f"error: {word}"
    assert set(left) <= {"x.png"}  # the image may be complete; the masks were never renamed
