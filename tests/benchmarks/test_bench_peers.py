"""benchmarks.bench_peers --quick runs end to end whichever peers are installed (Open3D and
Mitsuba 3 are optional: the bench extra), and says why a peer is left out.  Structure only:
nothing here is timed or compared with a target."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from builders import ROOT

pytestmark = pytest.mark.gl  # the raster masks are rendered


def test_the_peer_benchmark_runs_quick(tmp_path):
    """Every scene a row: the ray tracer's and the raster masks' times, and each of their
    ground truths (all outputs); each peer timed where it runs, else its reason printed; the
    pixels differing from the ray tracer's masks; the rays (one primary a pixel, at most one
    shadow ray a pixel and light); the ray tracer on 1 and 2 threads; exit status 0."""
    done = subprocess.run([sys.executable, "-m", "benchmarks.bench_peers", "--quick",
                           "--json", str(tmp_path / "p.json")],
                          cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads((tmp_path / "p.json").read_text())
    rows = result["scenes"]
    assert rows[0]["scene"] == "1k" and rows[0]["triangles"] == 962
    assert set(result["peers_skipped"]) == {"Open3D", "Mitsuba 3"}
    for peer, why in result["peers_skipped"].items():
        if why is not None:
            assert f"{peer} skipped: {why}" in done.stdout
    for row in rows:
        ran = {p for p, why in result["peers_skipped"].items() if why is None}
        assert set(row["ms"]) == {"ray tracer", "raster masks", "ray tracer, all outputs",
                                  "raster, all outputs"} | ran
        assert all(v["wall"] > 0 and v["cpu"] >= 0 for v in row["ms"].values())
        assert set(row["differing"]) == {"raster masks"} | ran
        width, height = row["size"]
        assert row["primary_rays"] == row["views"] * width * height
        assert 0 < row["shadow_rays"] <= row["primary_rays"] * row["lights"]
        assert set(row["threads"]["ms"]) == {"1", "2"} and row["threads"]["speedup"] > 0
        summary = row["summary"]
        assert summary["ours_ms"] == min(row["ms"]["ray tracer"]["wall"],
                                         row["ms"]["raster masks"]["wall"])
        assert (summary["ours_over_peer"] is None) == (not ran)
        assert summary["ns_per_ray_core"] > 0
        assert f"| {row['scene']} | {row['triangles']:,} |" in done.stdout
