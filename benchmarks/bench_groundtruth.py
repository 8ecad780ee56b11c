"""Benchmark (not a test): what each ground-truth output costs on a 100k-triangle frame, in
both renderers.

    python -m benchmarks.bench_groundtruth [--runs N] [--width W] [--height H]

The scene: `occluder_scene("100k")` (a floor and 20 icospheres, 102,402 triangles, 21 objects),
1280x720, one point light.  The rasterizer: `Renderer.render(outputs=...)` with the frame's own
outputs (image, lit, coverage) and then each ground-truth output added alone and all of them; the
ray tracer: `raytrace.shadow_masks` and `raytrace.ground_truth` with each output alone and all,
on one prebuilt Embree backend.  The variants are interleaved round by round (load slows all
alike) and each is the median of the rounds after a warm-up.  The target of the issue, casters
with at most 16 casting objects in at most 1 extra frame, is measured on the same generator with
16 spheres (`occluder_scene("100k", spheres=16)`: 81,922 triangles), its frame and + casters
interleaved in the same rounds.  `benchmarks.run` calls `measure` for BENCHMARKS.md.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

OUTPUTS = ("depth", "distance", "normal", "object_id", "facing", "casters")
FRAME = ("image", "lit", "coverage")
TARGET_CASTING = 16   # the target: casters with at most this many casting objects ...
TARGET_FRAMES = 1.0   # ... costs at most this many extra frames


def _stats(times: list[float]) -> dict:
    """Milliseconds: median, min, max of `times` (seconds), and how many."""
    ms = [t * 1e3 for t in times]
    return {"median": statistics.median(ms), "min": min(ms), "max": max(ms), "n": len(ms)}


def casting_objects(casters) -> int:
    """How many objects cast somewhere: the bits set in any pixel of `casters` (L, H, W, K)."""
    import numpy as np

    words = np.bitwise_or.reduce(casters.reshape(-1, casters.shape[-1]), axis=0)
    return sum(bin(int(w)).count("1") for w in words)


def _interleaved(variants: dict, runs: int) -> dict:
    """{label: stats} of calling each variant once per round, `runs` rounds after a warm-up;
    each stats also has "cpu": the same of the process's CPU time (every thread's, llvmpipe's
    too), which other sessions' load on the cores moves less than the wall clock."""
    for fn in variants.values():
        fn()
    times = {label: [] for label in variants}
    cpu = {label: [] for label in variants}
    for _ in range(runs):
        for label, fn in variants.items():
            start, start_cpu = time.perf_counter(), time.process_time()
            fn()
            times[label].append(time.perf_counter() - start)
            cpu[label].append(time.process_time() - start_cpu)
    return {label: _stats(t) | {"cpu": _stats(cpu[label])} for label, t in times.items()}


def measure(ctx, runs: int = 5, width: int = 1280, height: int = 720,
            size: str = "100k") -> dict:
    """Both renderers' costs (see the module) on `occluder_scene(size)` with one point light.
    ctx: a GL context for the rasterizer."""
    import raytrace
    from raytrace.masks import scene_backend
    from shadowvol import Renderer

    from .scenes import SIZES, occluder_scene

    scene = occluder_scene(size, 1, width, height)
    # the same generator with at most TARGET_CASTING spheres (a small size may have fewer)
    few = occluder_scene(size, 1, width, height, spheres=min(TARGET_CASTING, SIZES[size][0]))
    labels = ["frame"] + [f"+ {n}" for n in OUTPUTS] + ["+ all"]
    extras = [()] + [(n,) for n in OUTPUTS] + [OUTPUTS]
    with Renderer(scene, ctx) as r, Renderer(few, ctx) as r_few:
        variants = {label: (lambda e=e: r.render(outputs=FRAME + e))
                    for label, e in zip(labels, extras)}
        variants["few: frame"] = lambda: r_few.render(outputs=FRAME)
        variants["few: + casters"] = lambda: r_few.render(outputs=FRAME + ("casters",))
        raster = _interleaved(variants, runs)
        casting = casting_objects(r.render(outputs=FRAME + ("casters",)).casters)
        few_casting = casting_objects(r_few.render(outputs=FRAME + ("casters",)).casters)
    target = {"scene": few.name, "triangles": sum(len(o.faces) for o in few.objects),
              "objects": len(few.objects), "casting_objects": few_casting,
              "frame": raster.pop("few: frame"), "casters": raster.pop("few: + casters")}
    backend = scene_backend(scene, "embree")
    rt_variants = {"shadow_masks": lambda: raytrace.shadow_masks(scene, backend)}
    for label, e in zip(labels[1:], extras[1:]):
        rt_variants[label] = lambda e=e: raytrace.ground_truth(scene, e, backend)
    ray = _interleaved(rt_variants, max(2, runs // 2))
    return {"run": _run_info(),
            "scene": scene.name, "triangles": sum(len(o.faces) for o in scene.objects),
            "objects": len(scene.objects), "casting_objects": casting,
            "width": width, "height": height, "raster": raster, "raytrace": ray,
            "target": target}


def target_lines(res: dict) -> list[str]:
    """Markdown lines: the casters target on the scene with at most TARGET_CASTING casting
    objects (`measure`'s "target"), and casters' cost on the main scene beside it."""
    t = res.get("target")
    if not t:
        return []
    frame, casters = t["frame"]["median"], t["casters"]["median"]
    extra = (casters - frame) / frame
    main = res["raster"]
    main_extra = (main["+ casters"]["median"] - main["frame"]["median"]) / main["frame"]["median"]
    met = t["casting_objects"] <= TARGET_CASTING and extra <= TARGET_FRAMES
    cpu = ""
    if "cpu" in t["frame"]:
        f_cpu, c_cpu = t["frame"]["cpu"]["median"], t["casters"]["cpu"]["median"]
        cpu = (f"  Process CPU time (all threads) in the same rounds: frame {f_cpu:.0f} ms, "
               f"+ casters {c_cpu:.0f} ms: {(c_cpu - f_cpu) / f_cpu:+.2f} frames.")
    return [f"Target: casters with at most {TARGET_CASTING} casting objects costs at most "
            f"{TARGET_FRAMES:g} extra frame.  `{t['scene']}` ({t['triangles']:,} triangles, "
            f"{t['objects']} objects, {t['casting_objects']} casting), interleaved in the same "
            f"rounds: frame {frame:.0f} ms ({t['frame']['min']:.0f}-{t['frame']['max']:.0f}), "
            f"+ casters {casters:.0f} ms ({t['casters']['min']:.0f}-{t['casters']['max']:.0f}): "
            f"{extra:+.2f} frames, **{'met' if met else 'not met'}**.  (`{res['scene']}`, "
            f"{res['casting_objects']} casting: {main_extra:+.2f}.){cpu}"]


def _run_info() -> dict:
    """When and where: the commit, the UTC time and the load average (1/5/15 min)."""
    import datetime
    import os
    import subprocess

    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                            capture_output=True, text=True).stdout.strip() or "unknown"
    return {"commit": commit, "date": datetime.datetime.now(datetime.timezone.utc)
            .strftime("%Y-%m-%d %H:%M UTC"), "load": list(os.getloadavg())}


def table(res: dict) -> list[str]:
    """Markdown lines of a `measure` result."""
    frame = res["raster"]["frame"]["median"]
    masks = res["raytrace"]["shadow_masks"]["median"]
    lines = ["| outputs | raster (ms) | raster, extra / frame | ray tracer (ms) | "
             "ray tracer / masks |", "|---|---:|---:|---:|---:|"]
    for label, r in res["raster"].items():
        rt = res["raytrace"]["shadow_masks" if label == "frame" else label]
        name = "frame (image, lit, coverage) / masks" if label == "frame" else label
        lines.append(f"| {name} | {r['median']:.0f} | "
                     f"{(r['median'] - frame) / frame:+.2f} | {rt['median']:.0f} | "
                     f"{rt['median'] / masks:.2f} |")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--width", type=int, default=1280)
    ap.add_argument("--height", type=int, default=720)
    ap.add_argument("--into", type=Path, default=None, metavar="RESULTS_JSON",
                    help="also store the result as the `groundtruth` entry of a "
                         "benchmarks.run results.json (then `python -m benchmarks.run "
                         "--report-only` rewrites the report)")
    args = ap.parse_args(argv)
    from shadowvol.raster.platform.context import create_context

    ctx = create_context()
    try:
        res = measure(ctx, args.runs, args.width, args.height)
    finally:
        ctx.release()
    print(f"{res['scene']}: {res['triangles']:,} triangles, {res['objects']} objects "
          f"({res['casting_objects']} casting), one point light, "
          f"{res['width']}x{res['height']}\n")
    print("\n".join(table(res)))
    print()
    print("\n".join(target_lines(res)))
    if args.into is not None:
        import json

        results = json.loads(args.into.read_text())
        results["groundtruth"] = res
        args.into.write_text(json.dumps(results, indent=1, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
