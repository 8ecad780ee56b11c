"""Every benchmark of shadowvol in one reproducible run; writes BENCHMARKS.md and its plot.

    python -m benchmarks.run            # the full run (~12-15 min on 2 cores / llvmpipe)
    python -m benchmarks.run --quick    # a smoke run on small scenes (seconds), into --out

What it measures (medians of several runs after warm-up, with min and max), every ratio from
variants interleaved round by round in the same run:

* frames at 1280x720 of the procedural scenes of `scenes` (~1k, 100k and 1M triangles): the
  PLAIN moderngl frame of the same triangles (`plain`: one indexed draw, back-face culling,
  Blinn-Phong, RGBA8 read-back), the floor (our frame without shadow volumes), the shadowed
  frame (auto, CPU silhouettes) with 1, 2 and 4 point lights, GPU silhouettes, mask-only frames
  (`outputs=("lit", "coverage")`), and the opt-in back-face culling; and the least GL work of
  any exact frame (`plain.DepthFloor`; `plain.ImageFloor` and `plain.LightingFloor` for one
  that returns the image);
* each phase of a frame (`frame_timing`: glFinish-bracketed wall time), and silhouette extraction
  alone on the CPU and the GPU;
* the stencil-overflow check's cost on the shared meshes (bunny, teapot, Spot);
* a 36-view turntable (640x480, the five shared meshes and a floor, 3 lights): our masks and
  image per view against `raytrace.shadow_masks` of the same views;
* pyrender 0.1.45's shadow-mapped frame of the same scenes (spot and directional light);
* peak RSS of a 1M-triangle frame against the ray tracer's masks of it (separate processes);
* raytrace masks against raw embreex casts of the same rays (`bench_masks.measure`), and a full
  Whitted render.

Against the previous run: before it overwrites results.json, the run compares every ratio with
the previous run's (`regressions`: the commit of each, from `git rev-parse`) and prints each one
that got worse by more than 15 %, naming its benchmark; BENCHMARKS.md lists them too.

Where: the sections measured on this process's GL context are `sections`, those in processes
of their own (peak RSS, the other benchmark modules) `processes`, the machine `machine`; the
markdown is written by `report` from the measured numbers and links the hand-written history
of the optimisations (`benchmarks/OPTIMISATIONS.md`).  Mitsuba 3 is an optional peer that this
run does not install or time.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

from . import bench_groundtruth, regressions, report
from .machine import log, machine, maxrss_mb
from .processes import extras_section, rss_section
from .sections import (
    frame_section,
    objects_section,
    overflow_section,
    pyrender_section,
    raytrace_section,
    turntable_section,
)

ROOT = Path(__file__).resolve().parents[1]

FULL = dict(
    sizes=("1k", "100k", "1M"), lights=(1, 2, 4), size=(1280, 720),
    # (warm-up, timed) rounds per size: fewer at 1M, where one round takes seconds
    repeat={"1k": (2, 9), "100k": (2, 9), "1M": (1, 4)},
    phase_repeat={"1k": 5, "100k": 5, "1M": 2},
    # the check's cost is a few % of a 30-90 ms frame: more rounds than the frames, in
    # alternating order
    overflow_meshes=("bunny", "teapot", "spot"), overflow_repeat=(2, 25),
    turntable=dict(views=36, size=(640, 480)),
    pyrender_sizes=("1k", "100k", "1M"),
    pyrender_repeat={"1k": (2, 5), "100k": (2, 5), "1M": (1, 2)},
    rss_size="1M",
    mask_sizes=("100k", "1M"), mask_runs=5, bunny=True,
    whitted_size=(1280, 720), whitted_runs=3,
    truth_size="100k", truth_runs=7,
    # the Python of a frame against the number of objects (64 x 48: small draws)
    object_counts=(20, 1000, 5000), object_repeat=15,
)
QUICK = dict(
    sizes=("1k",), lights=(1, 2), size=(320, 180),
    repeat={"1k": (1, 2)}, phase_repeat={"1k": 1},
    overflow_meshes=("spot",), overflow_repeat=(1, 2),
    turntable=dict(views=2, size=(160, 120)),
    pyrender_sizes=("1k",), pyrender_repeat={"1k": (1, 2)},
    rss_size="1k",
    mask_sizes=("1k",), mask_runs=1, bunny=False,
    whitted_size=(160, 90), whitted_runs=1,
    truth_size="1k", truth_runs=1,
    object_counts=(20, 200), object_repeat=2,
)


def _arguments() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.run",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help="a smoke run: tiny scenes and sizes, one or two repeats")
    ap.add_argument("--out", type=Path, default=None,
                    help="folder for BENCHMARKS.md, the plot and results.json (default: the "
                         "checkout for a full run: BENCHMARKS.md, docs/benchmarks.png, "
                         "benchmarks/results.json; test-output/benchmarks-quick for --quick)")
    ap.add_argument("--no-pyrender", action="store_true", help="skip the pyrender peer")
    ap.add_argument("--no-extras", action="store_true",
                    help="skip the other issues' benchmark scripts (EXTRAS; a --quick run "
                         "skips them too)")
    ap.add_argument("--report-only", type=Path, metavar="RESULTS_JSON",
                    help="measure nothing: rewrite the markdown and the plot from a run's "
                         "results.json (e.g. after a change to the report's code)")
    return ap


def _paths(args) -> dict[str, Path]:
    """Where the markdown, the plot and results.json go (their folders made)."""
    if args.out is not None:
        paths = {"md": args.out / "BENCHMARKS.md", "png": args.out / "benchmarks.png",
                 "json": args.out / "results.json"}
    elif args.quick:
        out = ROOT / "test-output" / "benchmarks-quick"
        paths = {"md": out / "BENCHMARKS.md", "png": out / "benchmarks.png",
                 "json": out / "results.json"}
    else:
        paths = {"md": ROOT / "BENCHMARKS.md", "png": ROOT / "docs" / "benchmarks.png",
                 "json": ROOT / "benchmarks" / "results.json"}
    for p in paths.values():
        p.parent.mkdir(parents=True, exist_ok=True)
    return paths


def _measure(args, cfg: dict) -> dict:
    """Every section of the run, in order; the results as results.json holds them."""
    from shadowvol.raster.platform.context import create_context

    command = "python -m benchmarks.run" + (" --quick" if args.quick else "") + \
              (" --no-pyrender" if args.no_pyrender else "")
    started = time.perf_counter()
    ctx = create_context()
    try:
        results = {"command": command, "quick": args.quick, "machine": machine(ctx),
                   "config": {k: v for k, v in cfg.items()}}
        frame_rows, phases, sil, memory = frame_section(ctx, cfg)
        results.update(frames=frame_rows, phases=phases, silhouettes=sil, memory=memory)
        results["overflow"] = overflow_section(ctx, cfg)
        results["objects"] = objects_section(ctx, cfg)
        results["turntable"] = turntable_section(ctx, cfg)
        results["maxrss_after_frames_mb"] = maxrss_mb()
        results["pyrender"] = [] if args.no_pyrender else pyrender_section(ctx, cfg)
        results["maxrss_after_pyrender_mb"] = maxrss_mb()
        width, height = cfg["size"]
        results["groundtruth"] = bench_groundtruth.measure(
            ctx, cfg["truth_runs"], width, height, cfg["truth_size"])
        log("ground truth: all outputs "
            f"{results['groundtruth']['raster']['+ all']['median']:.0f} ms (raster)")
    finally:
        ctx.release()
    results["rss"] = rss_section(cfg)
    results["raytrace"] = raytrace_section(cfg)
    results["extras"] = [] if args.quick or args.no_extras else extras_section()
    results["maxrss_end_mb"] = maxrss_mb()
    results["machine"]["load_end"] = os.getloadavg()
    results["wall_s"] = time.perf_counter() - started
    return results


def _previous(path: Path) -> dict | None:
    """The previous run's results (the results.json this run replaces), or None."""
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def main(argv=None) -> int:
    args = _arguments().parse_args(argv)
    cfg = QUICK if args.quick else FULL
    paths = _paths(args)
    if args.report_only:
        results = json.loads(args.report_only.read_text())
        report.write(results, paths["md"], paths["png"])
        log(f"rewrote {paths['md']} and {paths['png']} from {args.report_only}")
        return 0

    previous = _previous(paths["json"])
    results = _measure(args, cfg)
    if previous is not None:
        # the guard against the next slowdown: every ratio worse than in the previous run
        results["previous"] = {"commit": regressions.commit(previous), "regressions": [
            g._asdict() for g in regressions.compare(results, previous)]}
        for line in regressions.report(results, previous):
            log(line)
    paths["json"].write_text(json.dumps(results, indent=1, default=str))
    report.write(results, paths["md"], paths["png"])
    log(f"wrote {paths['md']}, {paths['png']} and {paths['json']} "
        f"in {results['wall_s']:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
