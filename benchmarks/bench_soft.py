"""Benchmark (not a test): the cost of soft shadows, raster against the ray tracer.

    python benchmarks/bench_soft.py [--size 100k] [--width 1280] [--height 720] [--runs 3]

The benchmark's occluder scene (`benchmarks/scenes.py`) with its light made a square rect light
(1 x 1, facing down) of N samples.  It times, as medians of `--runs` frames after a warm-up:

1. a raster frame with the rect light for N = 1, 4, 16, 64, and with 1 and 4 point lights, so
   that one further sample can be set against one further point light;
2. the ray tracer's `lit_count` of the N = 16 frame (`raytrace.soft.lit_counts` on a prebuilt
   Embree backend; the BVH build is reported apart);

and prints a markdown table.  The issue's targets: one sample costs no more than one further
point light, and the raster frame is at least 3x faster than the ray tracer's count.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run from a checkout, installed or not
sys.path.insert(0, str(ROOT / "benchmarks"))

SAMPLES = (1, 4, 16, 64)


def median_time(fn, runs: int) -> float:
    fn()  # warm-up
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main(argv=None) -> int:
    from raytrace.masks import scene_backend
    from raytrace.soft import lit_counts
    from scenes import POINT_LIGHTS, occluder_scene, triangle_count
    from shadowvol.raster.renderer import Renderer
    from shadowvol.scene import AreaLight, PointLight

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", default="100k", help="the scene size (benchmarks/scenes.py)")
    ap.add_argument("--width", type=int, default=1280)
    ap.add_argument("--height", type=int, default=720)
    ap.add_argument("--runs", type=int, default=3, help="timed frames after a warm-up")
    args = ap.parse_args(argv)

    base = occluder_scene(args.size, 1, args.width, args.height)

    def rect(n: int) -> AreaLight:
        return AreaLight("rect", POINT_LIGHTS[0], normal=[0, -1, 0], size=[1.0, 1.0], samples=n)

    raster = {}
    with Renderer(base) as r:
        for n in SAMPLES:
            raster[f"rect N={n}"] = median_time(lambda: r.render(lights=(rect(n),)), args.runs)
        for k in (1, 4):
            lights = tuple(PointLight(p) for p in POINT_LIGHTS[:k])
            raster[f"{k} point lights"] = median_time(lambda: r.render(lights=lights),
                                                      args.runs)
    scene16 = base.replace(lights=(rect(16),))
    start = time.perf_counter()
    backend = scene_backend(scene16)
    build = time.perf_counter() - start
    ray16 = median_time(lambda: lit_counts(scene16, backend), args.runs)

    per_sample = (raster["rect N=16"] - raster["rect N=1"]) / 15
    per_light = (raster["4 point lights"] - raster["1 point lights"]) / 3
    print(f"{base.name}, {triangle_count(base):,} triangles, {args.width}x{args.height}, "
          f"medians of {args.runs} frames")
    print()
    print("| what | wall time (ms) |")
    print("|---|---:|")
    for what, t in raster.items():
        print(f"| raster frame, {what} | {t * 1e3:.0f} |")
    print(f"| ray tracer `lit_count`, rect N=16 (prebuilt backend) | {ray16 * 1e3:.0f} |")
    print(f"| Embree BVH build (once per scene) | {build * 1e3:.0f} |")
    print()
    print(f"one further sample: {per_sample * 1e3:.1f} ms; one further point light: "
          f"{per_light * 1e3:.1f} ms (target: sample <= point light)")
    print(f"ray tracer / raster at N=16: {ray16 / raster['rect N=16']:.2f}x (target >= 3x)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
