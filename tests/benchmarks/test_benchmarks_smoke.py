"""The benchmark command runs end to end (`python -m benchmarks.run --quick`, tiny scenes) and
writes a report of the expected shape.  Structure only: nothing here is timed or compared with a
target.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from builders import ROOT

pytestmark = pytest.mark.gl  # the child processes render

SECTIONS = ["## Headline ratios and targets", "## Frames at",
            "### What no exact shadow-volume frame can go below here", "## Phases (one light)",
            "## pyrender 0.1.45, the same scenes", "## Ray tracer", "## Ground truth",
            "## Memory", "## Python a frame against the number of objects"]
# with the shared meshes beside the checkout (or its parent) the real-mesh sections run too
MESH_SECTIONS = ["## The stencil-overflow check on real meshes", "## Turntable"]


def test_quick_benchmark_run_writes_the_report(tmp_path):
    done = subprocess.run([sys.executable, "-m", "benchmarks.run", "--quick", "--out",
                           str(tmp_path)], cwd=ROOT, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    md = (tmp_path / "BENCHMARKS.md").read_text()
    results = json.loads((tmp_path / "results.json").read_text())
    for heading in SECTIONS + (MESH_SECTIONS if results["overflow"] else []):
        assert heading in md, heading
    assert "python -m benchmarks.run --quick" in md
    assert "llvmpipe" in md or "GL**:" in md
    png = (tmp_path / "benchmarks.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    for key in ("machine", "frames", "phases", "silhouettes", "overflow", "turntable",
                "pyrender", "rss", "raytrace", "memory", "groundtruth", "objects"):
        assert key in results, key
    # the Python of a frame, for each number of objects, inside its whole frame
    assert [row["objects"] for row in results["objects"]] == [21, 201]
    for row in results["objects"]:
        for part in ("masks", "image + masks"):
            t = row[part]
            assert 0 < t["python"]["median"] <= t["frame"]["median"]
    frame = results["frames"][0]["times"]
    assert {"plain", "depth floor", "mask floor", "image floor", "lighting: lit",
            "lighting: flat", "floor", "auto/cpu x1", "masks/cpu x1", "auto/gpu x1"} <= set(frame)
    assert all({"median", "min", "max"} <= set(s) for s in frame.values())
    # every headline row has a number and a verdict
    rows = md.split("## Headline ratios and targets")[1].split("##")[0]
    assert rows.count("**met**") + rows.count("not met") >= 2


def test_the_mitsuba_peer_runs_or_says_why_not(tmp_path):
    """benchmarks.bench_mitsuba on a tiny scene: with Mitsuba 3 installed (the bench extra) a row
    of times (ours, the ray tracer's, Mitsuba's, and the bound: the depth and mask floors and the
    volume pass) and pixel counts; without it, the reason, and exit status 0 either way."""
    done = subprocess.run([sys.executable, "-m", "benchmarks.bench_mitsuba",
                           "--sizes", "1k", "--width", "64", "--height", "48", "--runs", "1",
                           "--json", str(tmp_path / "m.json")],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    results = json.loads((tmp_path / "m.json").read_text())
    try:
        import mitsuba  # noqa: F401
    except ImportError:
        assert "Mitsuba 3 is not installed" in results["skipped"]
        assert done.stdout.startswith("skipped:")
        return
    (row,) = results["scenes"]
    assert row["triangles"] == 962
    assert set(row["ms"]) == {"ours, masks only", "raytrace.shadow_masks", "Mitsuba 3",
                              "depth floor", "mask floor", "volume pass"}
    assert all(row["ms"][k]["median"] > 0 for k in ("depth floor", "mask floor", "volume pass"))
    # the CPU time of a frame, during the call and after it returns, for ours and Mitsuba
    assert set(row["cpu_ms"]) == {"ours, masks only", "Mitsuba 3"}
    for c in row["cpu_ms"].values():
        assert c["during"]["median"] > 0 and c["after"]["median"] >= 0
    # the same scene, the same pixel-centre rays: the masks agree but for a few edge pixels
    assert row["differing_mitsuba"] < 0.05 * 64 * 48 and row["differing_ours"] < 0.05 * 64 * 48
    assert "| occluders-1k |" in done.stdout


def test_time_to_rmse_runs_with_or_without_mitsuba(tmp_path):
    """benchmarks.bench_time_to_rmse --quick (24 x 24, 4 and 64 spp, 2 runs): every variant's
    error, over every pixel and away from the light, falls at least 2x (1/sqrt(spp): 4x) with
    16x the samples against the reference, and has times; Mitsuba's rows where it is installed, else the
    reason in the first line and ours alone; exit status 0 either way."""
    done = subprocess.run([sys.executable, "-m", "benchmarks.bench_time_to_rmse", "--quick",
                           "--json", str(tmp_path / "t.json")],
                          cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    results = json.loads((tmp_path / "t.json").read_text())
    ours = {k for k in results["variants"] if k.startswith("ours")}
    assert len(ours) == 3 and "ours now: power, sobol, RR 5" in ours
    try:
        import mitsuba  # noqa: F401
    except ImportError:
        assert "Mitsuba 3 is not installed" in results["peer_missing"]
        assert "ours alone" in done.stdout.splitlines()[0]
        assert set(results["variants"]) == ours
    else:
        assert results["peer_missing"] is None and len(results["variants"]) == 5
        assert results["reference"].startswith("Mitsuba 3")
    for v in results["variants"].values():
        assert v["rmse"][1] < v["rmse"][0] / 2, v["rmse"]
        assert v["rmse_unlit"][1] < v["rmse_unlit"][0] / 2, v["rmse_unlit"]
        assert min(v["cpu_s"]) > 0


def test_the_batch_memory_benchmark_runs(tmp_path):
    """benchmarks.bench_batch_memory --quick: a short jittered batch, every frame made, RSS
    sampled through the run and the second half's growth reported (not judged here: the
    quick run is still filling the renderer's bounded caches)."""
    out = tmp_path / "memory.json"
    done = subprocess.run([sys.executable, "-m", "benchmarks.bench_batch_memory", "--quick",
                           "--json", str(out)], cwd=ROOT, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "300 of 300 jittered frames at 8x6" in done.stdout
    assert "second half's growth" in done.stdout and "goal <= 5 MB" in done.stdout
    result = json.loads(out.read_text())
    assert result["made"] == result["frames"] == 300 and result["samples"] >= 5
    rss = result["rss_mb"]
    assert 0 < rss["start"] <= rss["middle"] and rss["end"] > 0
    growth = result["second_half_growth_mb"]
    assert growth == pytest.approx(rss["end"] - rss["middle"], abs=0.1)


def test_the_mitsuba_soft_peer_runs_or_says_why_not(tmp_path):
    """benchmarks.bench_mitsuba_soft on a tiny soft.toml: with Mitsuba 3 installed, its direct
    integrator's penumbra against the exact irradiance (no bias seen at p >= 0.01, and a 2%
    error seen); without it, the reason and exit status 0."""
    done = subprocess.run([sys.executable, "-m", "benchmarks.bench_mitsuba_soft", "--size",
                           "32x24", "--calls", "48", "--json", str(tmp_path / "m.json")],
                          cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    r = json.loads((tmp_path / "m.json").read_text())
    try:
        import mitsuba  # noqa: F401
    except ImportError:
        assert "Mitsuba 3 is not installed" in r["skipped"]
        assert done.stdout.startswith("skipped:")
        return
    assert r["variant"] == "scalar_rgb" and r["penumbra_pixels"] > 50
    assert r["p_value"] >= 0.01 and r["p_value_2_percent_off"] < 0.01, r


def test_the_masks_choice_benchmark_runs(tmp_path):
    """bench_fastest --quick: both renderers timed per scene, auto's choice against them, the
    model refitted and a fresh process's one-off costs (structure only, nothing compared)."""
    out = tmp_path / "fastest.json"
    done = subprocess.run([sys.executable, "-m", "benchmarks.bench_fastest", "--quick", "--runs",
                           "1", "--json", str(out)], cwd=ROOT, capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads(out.read_text())
    assert len(result["scenes"]) == 2
    for row in result["scenes"]:
        assert row["chosen"] in ("shadowvol", "raytrace") and row["chosen_over_best"] >= 1.0
        assert set(row["ms"]) == {"shadowvol", "raytrace"}
    assert set(result["first"]) == {"shadowvol", "raytrace, packets", "raytrace, single rays"}
    assert "auto chose the faster renderer on" in done.stdout


def test_the_exact_soft_medians_run(capsys):
    """`python -m benchmarks.bench_exact_soft --medians N`'s loop (small frames): a line a
    frame with both medians and their ratio (nothing timed here)."""
    pytest.importorskip("shapely")
    from benchmarks import bench_exact_soft
    bench_exact_soft.medians(16, 2, bunny_sizes=(8,), own=False)
    out = capsys.readouterr().out
    lines = [line for line in out.splitlines() if " = " in line]
    assert lines[0].lstrip().startswith("soft.toml 16x12:")
    assert lines[1].lstrip().startswith("blob")
    assert all(line.split(" = ")[1].split("x")[0].replace(".", "").isdigit() for line in lines)
    assert all(line.split("paired ")[1].split("x")[0].replace(".", "").isdigit()
               for line in lines)


def test_the_exact_soft_paired_run(capsys):
    """`python -m benchmarks.bench_exact_soft --paired DIR`'s loop (small frames), this
    checkout paired with itself: a line a frame with both medians, the paired ratio and the
    same bytes (nothing timed here)."""
    pytest.importorskip("shapely")
    from benchmarks import bench_exact_soft
    bench_exact_soft.paired(bench_exact_soft.exact_soft, rounds=2, bunny_sizes=(8,), width=16,
                            own=False)
    lines = [line for line in capsys.readouterr().out.splitlines() if "new / old" in line]
    names = [line.split(":")[0].strip() for line in lines]
    assert names[:2] == ["soft.toml 16x12", "blob 48x48"]
    assert len(lines) == (3 if bench_exact_soft.BUNNY.is_file() else 2)
    for line in lines:
        assert line.endswith("the same bytes"), line
        ratio = line.split("new / old ")[1].split("x")[0]
        assert float(ratio) > 0


def test_the_exact_soft_by_size_run(capsys):
    """`bench_exact_soft.soft_by_size`' loop (small frames): a line a size with both medians
    and their ratio (nothing timed here)."""
    pytest.importorskip("shapely")
    from benchmarks import bench_exact_soft
    bench_exact_soft.soft_by_size((16, 24))
    lines = [line for line in capsys.readouterr().out.splitlines() if " = " in line]
    assert [line.split(":")[0].strip() for line in lines] == ["16x12", "24x18"]
    assert all(float(line.split(" = ")[1].rstrip("x")) > 0 for line in lines)


def test_the_paired_package_is_imported_beside_this_one(tmp_path, monkeypatch):
    """`bench_exact_soft.other_exact_soft`: DIR's raytrace imported as `raytrace_paired` (its
    relative imports its own, not this checkout's); a DIR without one refused, named."""
    import sys
    from benchmarks import bench_exact_soft
    monkeypatch.setattr(sys, "path", list(sys.path))         # as it was, after
    package = tmp_path / "raytrace"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "helper.py").write_text("WHO = 'the old one'\n")
    (package / "exact_soft.py").write_text("from .helper import WHO\n")
    try:
        module = bench_exact_soft.other_exact_soft(str(tmp_path))
        assert module.__name__ == "raytrace_paired.exact_soft" and module.WHO == "the old one"
    finally:
        for name in [m for m in sys.modules if m.split(".")[0] == "raytrace_paired"]:
            del sys.modules[name]
    with pytest.raises(SystemExit, match="no raytrace/exact_soft.py"):
        bench_exact_soft.other_exact_soft(str(tmp_path / "nowhere"))


def test_the_exact_soft_light_sides_run(capsys):
    """`python -m benchmarks.bench_exact_soft --light-sides`' loop (the blob, small): a line a
    light side with the penumbra's share and both medians (nothing timed here)."""
    pytest.importorskip("shapely")
    from benchmarks import bench_exact_soft
    bench_exact_soft.light_sides(12, sides=(0.25, 2.0), calls=1, make=bench_exact_soft.blob_scene)
    lines = [line for line in capsys.readouterr().out.splitlines() if "side " in line]
    assert [line.split(":")[0].strip() for line in lines] == ["side 0.25", "side 2"]
    shares = [float(line.split("penumbra ")[1].split("%")[0]) for line in lines]
    assert 0 < shares[0] < shares[1] <= 100     # a larger light: a wider penumbra
