"""benchmarks.regressions: a run's ratios against the previous run's, on synthetic results.json
files (nothing here is timed): a ratio worse by more than 15 % is named, one within it, a
machine twice as slow, or a speed-up that grew is not; the command's output and status."""

from __future__ import annotations

import copy
import json
import subprocess
import sys

import pytest
from builders import ROOT

from benchmarks import regressions


def t(ms: float) -> dict:
    return {"median": ms, "min": ms, "max": ms, "n": 3}


def results(commit: str = "aaaaaaa") -> dict:
    """A run's results.json as `benchmarks.run` writes it, cut to what the ratios read."""
    return {
        "machine": {"commit": commit},
        "frames": [{"size": "100k", "triangles": 102402,
                    "times": {"plain": t(10.0), "auto/cpu x1": t(13.0),
                              "masks/cpu x1": t(11.0), "auto/cpu x4": t(19.0)}}],
        "overflow": [],
        "pyrender": [{"size": "100k", "light": "spot",
                      "times": {"auto/cpu": t(13.0), "pyrender shadowed": t(260.0)}}],
        "turntable": {"views": 36, "ours": t(90.0), "ours_masks": t(65.0),
                      "raytrace": t(150.0)},
        "raytrace": {"masks": [{"scene": "occluders 100k", "masks": t(0.08), "raw": t(0.07)}]},
        "groundtruth": {"raster": {"frame": t(50.0), "+ all": t(70.0)},
                        "raytrace": {"shadow_masks": t(80.0), "+ all": t(120.0)}},
    }


def scaled(r: dict, factor: float) -> dict:
    """Every time of a run times `factor` (a slower or busier machine)."""
    out = copy.deepcopy(r)

    def walk(x):
        if isinstance(x, dict):
            if set(x) >= {"median", "min", "max"}:
                for k in ("median", "min", "max"):
                    x[k] *= factor
            else:
                for v in x.values():
                    walk(v)
        elif isinstance(x, list):
            for v in x:
                walk(v)
    walk(out)
    return out


def names(new: dict, old: dict) -> list[str]:
    return [g.name for g in regressions.compare(new, old)]


def test_the_same_run_and_a_slower_machine_have_no_regression():
    old = results()
    assert names(old, old) == []
    assert names(scaled(old, 2.0), old) == []  # ratios, not times
    assert len(regressions.ratios(old)) >= 10


@pytest.mark.parametrize("factor, flagged", [(1.10, False), (1.20, True)])
def test_a_frame_slower_against_its_plain_frame(factor, flagged):
    old, new = results(), results("bbbbbbb")
    new["frames"][0]["times"]["masks/cpu x1"]["median"] *= factor
    found = names(new, old)
    assert ("frames 100k: masks/cpu x1 / plain" in found) == flagged
    assert ("headline: 100k: mask-only frame (lit + coverage) / plain frame" in found) == flagged


def test_the_ray_tracers_slowdown_is_flagged_not_taken_for_a_speed_up():
    """The issue-40 regression: raytrace.shadow_masks 4x slower on the turntable, the
    rasterizer unchanged."""
    old, new = results(), results("bbbbbbb")
    new["turntable"]["raytrace"]["median"] *= 4
    new["raytrace"]["masks"][0]["masks"]["median"] *= 4
    found = regressions.compare(new, old)
    assert [g.name for g in found] == [
        "turntable: raytrace.shadow_masks / ours, masks only (per view)",
        "raytrace occluders 100k: shadow_masks / raw Embree casts of its rays"]
    assert found[0].worse == pytest.approx(4.0)


def test_a_speed_up_that_shrinks_is_a_regression_and_one_that_grows_is_not():
    old, new = results(), results("bbbbbbb")
    new["pyrender"][0]["times"]["pyrender shadowed"]["median"] *= 0.8  # peer faster: worse
    assert "pyrender 100k, spot: pyrender shadowed / ours (auto, CPU)" in names(new, old)
    assert names(old, new) == []  # the other way round it grew


def test_the_command_names_the_commits_and_each_regression(tmp_path):
    old, new = results("aaaaaaa"), results("bbbbbbb")
    new["groundtruth"]["raytrace"]["+ all"]["median"] *= 1.5
    (tmp_path / "old.json").write_text(json.dumps(old))
    (tmp_path / "new.json").write_text(json.dumps(new))
    done = subprocess.run([sys.executable, "-m", "benchmarks.regressions",
                           str(tmp_path / "new.json"), str(tmp_path / "old.json")],
                          cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert done.returncode == 1, done.stderr
    lines = done.stdout.splitlines()
    assert "commit aaaaaaa" in lines[0] and "1 of" in lines[0]
    assert lines[1].startswith("  REGRESSION ground truth raytrace: + all / shadow_masks: 1.5 "
                               "-> 2.25 (+50% worse)")
    same = subprocess.run([sys.executable, "-m", "benchmarks.regressions",
                           str(tmp_path / "old.json"), str(tmp_path / "old.json")],
                          cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert same.returncode == 0 and "0 of" in same.stdout



def with_extras(r: dict, packets_ns: float = 50.0, peer_ms: float = 100.0,
                chosen_over_best: float = 1.0) -> dict:
    """`r` with the extras `benchmarks.run` now records (`processes.EXTRAS`): bench_packets',
    bench_peers' and bench_fastest's --json results, cut to what the ratios read."""
    out = copy.deepcopy(r)
    packets = [{"rays": "shadow (occluded)", "backend": b, "threads": 2,
                "wall_ns": 60.0 if b == "single" else packets_ns} for b in ("single", "packets")]
    peers = [{"scene": "100k", "ms": {"ray tracer": {"wall": 110.0}, "raster masks":
                                      {"wall": 30.0}, "Open3D": {"wall": peer_ms}}}]
    choices = [{"scene": "turntable", "pixels": 307200, "lights": 3,
                "chosen_over_best": chosen_over_best}]
    out["extras"] = [{"script": "bench_packets.py", "results": {"rows": packets}},
                     {"script": "bench_peers.py", "results": {"scenes": peers}},
                     {"script": "bench_fastest.py", "results": {"scenes": choices}},
                     {"script": "bench_viewer.py", "results": None}]
    return out


def test_the_extras_ratios_are_guarded_too():
    """Embree's packets losing their lead over single rays, our masks falling behind a peer,
    and auto choosing the slower renderer are each flagged; the same extras are not."""
    old = with_extras(results())
    assert names(with_extras(results("bbbbbbb")), old) == []
    assert names(with_extras(results("bbbbbbb"), packets_ns=58.0), old) == [
        "bench_packets shadow (occluded), 2 threads: single / packets (wall)"]
    assert names(with_extras(results("bbbbbbb"), peer_ms=50.0), old) == [
        "bench_peers 100k: ours (the faster) / the best peer"]
    assert names(with_extras(results("bbbbbbb"), chosen_over_best=1.5), old) == [
        "bench_fastest turntable (307,200 px, 3 lights): auto's choice / the faster"]
