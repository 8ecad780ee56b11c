"""benchmarks.bench_soba on a tiny run: it counts the SOBA pairs it made and reports them, or,
without the shared meshes, says why it skipped (exit status 0 either way)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from builders import MODELS, ROOT

pytestmark = pytest.mark.gl  # the child process renders


def _run(tmp_path, *args):
    out = tmp_path / "r.json"
    done = subprocess.run([sys.executable, "-m", "benchmarks.bench_soba", "--pairs", "30",
                           "--views", "2", "--width", "48", "--height", "36", "--json",
                           str(out), *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    return done.stdout, json.loads(out.read_text())


def test_without_the_meshes_it_says_why(tmp_path):
    stdout, result = _run(tmp_path, "--models", str(tmp_path / "none"))
    assert "skipped" in result and str(tmp_path / "none") in stdout


def test_a_tiny_run_makes_the_pairs_it_reports(tmp_path):
    if not (MODELS / "bunny.obj").is_file():
        pytest.skip(f"the shared meshes are not in {MODELS}")
    stdout, result = _run(tmp_path, "--models", str(MODELS))
    assert result["pairs"] >= 30 and result["frames"] == 2 * result["scenes"]
    assert result["pairs_per_s"] == pytest.approx(result["pairs"] / result["seconds"])
    assert f"| {result['pairs']:,} |" in stdout and result["peak_rss_mb"] > 0
