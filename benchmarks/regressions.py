"""A run's ratios against the previous run's: every one that got worse by more than 15 %.

    python -m benchmarks.regressions NEW_RESULTS_JSON OLD_RESULTS_JSON [--threshold 0.15]

`benchmarks.run` calls `compare` on the results.json it is about to overwrite and prints the
regressions (and keeps them in the new results.json).  Only ratios are compared, never
times: each is two numbers measured in the same run (a frame against the plain frame of the
same triangles, the ray tracer's masks against raw Embree casts of the same rays, against
the rasterizer's view of the same turntable), so a slower or busier machine moves both.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import NamedTuple

from .report.ratios import headline, med

THRESHOLD = 0.15
# the headline rows the named ratios below replace (their direction is ambiguous: a slower
# ray tracer would look like a larger speed-up of the rasterizer)
REPLACED = ("turntable",)


class Ratio(NamedTuple):
    """value: the ratio; lower: True where a lower ratio is better (a cost), False where a
    higher one is (a speed-up)."""

    value: float
    lower: bool


class Regression(NamedTuple):
    name: str
    old: float
    new: float
    worse: float  # how much worse, as a factor (1.2: 20 % worse)


def ratios(results: dict) -> dict[str, Ratio]:
    """Every ratio of a run (`benchmarks.run`'s results), named by its benchmark."""
    out: dict[str, Ratio] = {}
    for what, value, target, _ in headline(results):
        if value is not None and not what.startswith(REPLACED):
            out[f"headline: {what}"] = Ratio(value, target.startswith("≤"))
    for row in results.get("frames", []):
        for key in row["times"]:
            if key != "plain":
                out[f"frames {row['size']}: {key} / plain"] = Ratio(
                    med(row, key) / med(row, "plain"), True)
    for row in results.get("pyrender", []):
        out[f"pyrender {row['size']}, {row['light']}: pyrender shadowed / ours (auto, CPU)"] = \
            Ratio(med(row, "pyrender shadowed") / med(row, "auto/cpu"), False)
    t = results.get("turntable") or {}
    if t:
        out["turntable: raytrace.shadow_masks / ours, masks only (per view)"] = Ratio(
            t["raytrace"]["median"] / t["ours_masks"]["median"], True)
        out["turntable: ours, masks + image / masks only (per view)"] = Ratio(
            t["ours"]["median"] / t["ours_masks"]["median"], True)
    for row in (results.get("raytrace") or {}).get("masks", []):
        out[f"raytrace {row['scene']}: shadow_masks / raw Embree casts of its rays"] = Ratio(
            row["masks"]["median"] / row["raw"]["median"], True)
    out.update(extras_ratios(results))
    truth = results.get("groundtruth") or {}
    for renderer, base in (("raster", "frame"), ("raytrace", "shadow_masks")):
        times = truth.get(renderer) or {}
        if base in times and "+ all" in times:
            out[f"ground truth {renderer}: + all / {base}"] = Ratio(
                times["+ all"]["median"] / times[base]["median"], True)
    return out


def _extra(results: dict, script: str) -> dict:
    """What the extra `script` (`benchmarks.processes.EXTRAS`) wrote to its --json, or {}."""
    for row in results.get("extras") or []:
        if row.get("script") == script and isinstance(row.get("results"), dict):
            return row["results"]
    return {}


def extras_ratios(results: dict) -> dict[str, Ratio]:
    """The ratios of the other benchmark modules that measure two variants in one run: Embree's
    packets against its single rays (`bench_packets`), our masks against the best peer
    (`bench_peers`), auto's choice against the faster renderer (`bench_fastest`)."""
    out: dict[str, Ratio] = {}
    rows = {(r["rays"], r["backend"], r["threads"]): r
            for r in _extra(results, "bench_packets.py").get("rows", [])}
    for (rays, backend, threads), r in rows.items():
        if backend == "packets" and (rays, "single", threads) in rows:
            out[f"bench_packets {rays}, {threads} threads: single / packets (wall)"] = Ratio(
                rows[rays, "single", threads]["wall_ns"] / r["wall_ns"], False)
    for r in _extra(results, "bench_peers.py").get("scenes", []):
        ms = {k: v["wall"] for k, v in r["ms"].items()}
        peer = min((ms[k] for k in ("Open3D", "Mitsuba 3") if k in ms), default=None)
        if peer:
            out[f"bench_peers {r['scene']}: ours (the faster) / the best peer"] = Ratio(
                min(ms["ray tracer"], ms["raster masks"]) / peer, True)
    for r in _extra(results, "bench_fastest.py").get("scenes", []):
        out[f"bench_fastest {r['scene']} ({r['pixels']:,} px, {r['lights']} lights): auto's "
            "choice / the faster"] = Ratio(r["chosen_over_best"], True)
    return out


def compare(new: dict, old: dict, threshold: float = THRESHOLD) -> list[Regression]:
    """The ratios of run `new` worse than in run `old` by more than `threshold` (0.15: 15 %),
    worst first; ratios in only one of the runs are not compared."""
    before, after = ratios(old), ratios(new)
    out = []
    for name, r in after.items():
        if name not in before or before[name].value <= 0 or r.value <= 0:
            continue
        worse = (r.value / before[name].value if r.lower else before[name].value / r.value)
        if worse > 1.0 + threshold:
            out.append(Regression(name, before[name].value, r.value, worse))
    return sorted(out, key=lambda g: -g.worse)


def commit(results: dict) -> str:
    return (results.get("machine") or {}).get("commit", "?")


def report(new: dict, old: dict, threshold: float = THRESHOLD) -> list[str]:
    """The lines `benchmarks.run` prints: the commits compared, then one line a regression."""
    found = compare(new, old, threshold)
    lines = [f"against the previous run (commit {commit(old)}): {len(found)} of "
             f"{len(set(ratios(new)) & set(ratios(old)))} ratios worse by more than "
             f"{threshold:.0%}"]
    lines += [f"  REGRESSION {g.name}: {g.old:.3g} -> {g.new:.3g} ({g.worse - 1:+.0%} worse)"
              for g in found]
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.regressions",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("new", type=Path, help="this run's results.json")
    ap.add_argument("old", type=Path, help="the previous run's results.json")
    ap.add_argument("--threshold", type=float, default=THRESHOLD)
    args = ap.parse_args(argv)
    new, old = (json.loads(p.read_text()) for p in (args.new, args.old))
    print("\n".join(report(new, old, args.threshold)))
    return 1 if compare(new, old, args.threshold) else 0


if __name__ == "__main__":
    sys.exit(main())
