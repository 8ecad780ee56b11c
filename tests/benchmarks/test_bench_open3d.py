"""benchmarks.bench_open3d runs end to end, or says why not (Open3D is an optional peer: the
bench extra).  Structure only: nothing here is timed or compared with a target."""

from __future__ import annotations

import json
import subprocess
import sys

from builders import ROOT


def test_the_open3d_peer_runs_or_says_why_not(tmp_path):
    """benchmarks.bench_open3d: with Open3D (the bench extra) a row per scene with our masks'
    and Open3D's times and the pixels where they differ; without it, the reason; exit 0."""
    done = subprocess.run([sys.executable, "-m", "benchmarks.bench_open3d", "--runs", "1",
                           "--json", str(tmp_path / "o.json")],
                          cwd=ROOT, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    if done.stdout.startswith("skipped:"):
        assert "pip install open3d-cpu" in done.stdout
        return
    rows = json.loads((tmp_path / "o.json").read_text())["scenes"]
    assert rows and all(set(r["ms"]) == {
        "raytrace.shadow_masks (built backend)", "raytrace.shadow_masks (with its build)",
        "Open3D (built scene)", "Open3D (with its build)"} for r in rows)
    assert all(v["wall"] > 0 for r in rows for v in r["ms"].values())
