"""The `alone` marker (tests/alone.py) under pytest-xdist: a marked test's run overlaps no
other worker's test; without the plugin the same tests do overlap (so the check can fail)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

pytest.importorskip("xdist", reason="the marker only acts under pytest-xdist (the test extra)")

TESTS = Path(__file__).resolve().parent

TIMED = textwrap.dedent("""
    import os, time
    from pathlib import Path
    import pytest

    def spell(name, seconds):
        start = time.monotonic()
        time.sleep(seconds)
        with open(Path(os.environ["SPELLS"]), "a") as f:
            f.write(f"{name} {start} {time.monotonic()}\\n")
    """)


def _spells(tmp_path: Path, plugin: bool) -> tuple[tuple[float, float], list]:
    """The alone test's (start, end) and the other tests' from one `pytest -n 2` run."""
    folder = tmp_path / ("with" if plugin else "without")
    folder.mkdir()
    (folder / "timed.py").write_text(TIMED)
    (folder / "test_alone_one.py").write_text(
        "import pytest\nfrom timed import spell\n\n\n@pytest.mark.alone\n"
        "def test_alone():\n    spell('alone', 1.0)\n")
    (folder / "test_others.py").write_text(
        "import pytest\nfrom timed import spell\n\n\n@pytest.mark.parametrize('k', range(6))\n"
        "def test_other(k):\n    spell(f'other{k}', 0.25)\n")
    log = folder / "spells.txt"
    argv = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-n", "2",
            "--dist", "loadfile", "-W", "ignore::pytest.PytestUnknownMarkWarning",
            "--rootdir", str(folder), str(folder)]
    if plugin:
        argv[3:3] = ["-p", "alone"]
    done = subprocess.run(argv, cwd=folder, capture_output=True, text=True, timeout=120,
                          env={**os.environ, "SPELLS": str(log),
                               "PYTHONPATH": f"{TESTS}:{folder}"})
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    rows = [line.split() for line in log.read_text().splitlines()]
    alone = next((float(a), float(b)) for name, a, b in rows if name == "alone")
    others = [(float(a), float(b)) for name, a, b in rows if name != "alone"]
    assert len(others) == 6
    return alone, others


def _overlaps(alone, others) -> int:
    return sum(a < alone[1] and b > alone[0] for a, b in others)


def test_an_alone_test_runs_with_no_other_beside_it(tmp_path):
    alone, others = _spells(tmp_path, plugin=True)
    assert _overlaps(alone, others) == 0, (alone, others)
    # and the other worker ran its tests, before or after it
    assert all(b <= alone[0] or a >= alone[1] for a, b in others)


def test_without_the_plugin_they_overlap(tmp_path):
    alone, others = _spells(tmp_path, plugin=False)
    assert _overlaps(alone, others) > 0, (alone, others)
