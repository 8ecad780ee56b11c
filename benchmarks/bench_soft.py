"""Benchmark (not a test): the cost of soft shadows, raster against the ray tracer.

    python -m benchmarks.bench_soft [--size 100k] [--width 1280] [--height 720] [--rounds 9]

The benchmark's occluder scene (`benchmarks.scenes`) with its light made a square rect light
(1 x 1, facing down) of N samples.  It times, interleaved round by round after one warm-up round
(so that load from other processes slows every variant alike):

1. a raster frame with the rect light for N = 1, 4, 16, 64, and with 1 and 4 point lights, so
   that one further sample can be set against one further point light;
2. the ray tracer's `lit_count` of the N = 16 frame (`raytrace.soft.lit_counts` on a prebuilt
   Embree backend, all its threads; the BVH build is reported apart);

and prints a markdown table of medians and min-max over the rounds.  The issue's targets: one
sample costs no more than one further point light, and the raster frame is at least 3x faster
than the ray tracer's count.  Differences and ratios are taken within each round (the frames
of one round ran under the same load) and their median is reported.  One renderer draws every
variant: its kept volumes (`CpuVolumes`) hold all their lights, as they would for a stream of
frames of one setup, and the side quads built in the timed rounds are counted (0 expected).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

SAMPLES = (1, 4, 16, 64)
RAY = "ray tracer `lit_count`, rect N=16 (prebuilt backend)"


def interleaved(fns: dict, rounds: int, started: list) -> dict[str, list[float]]:
    """{name: [seconds per round]}: one untimed warm-up round, then `rounds` rounds in which
    every function runs once, in turn; `started` gets one item as each round begins."""
    times: dict[str, list[float]] = {name: [] for name in fns}
    for r in range(rounds + 1):
        started.append(r)
        for name, fn in fns.items():
            start = time.perf_counter()
            fn()
            if r:
                times[name].append(time.perf_counter() - start)
    return times


def spread(values_ms: list[float], digits: int = 0) -> str:
    """"median (min-max)" of `values_ms`."""
    return (f"{statistics.median(values_ms):.{digits}f} "
            f"({min(values_ms):.{digits}f}-{max(values_ms):.{digits}f})")


def main(argv=None) -> int:
    from raytrace.masks import scene_backend
    from raytrace.soft import lit_counts
    from shadowvol import PointLight, Renderer
    from shadowvol.scene import AreaLight

    from .scenes import POINT_LIGHTS, occluder_scene, triangle_count

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", default="100k", help="the scene size (benchmarks/scenes.py)")
    ap.add_argument("--width", type=int, default=1280)
    ap.add_argument("--height", type=int, default=720)
    ap.add_argument("--rounds", "--runs", type=int, default=9,
                    help="timed rounds after a warm-up round (every variant once a round)")
    args = ap.parse_args(argv)

    base = occluder_scene(args.size, 1, args.width, args.height)

    def rect(n: int) -> AreaLight:
        return AreaLight("rect", POINT_LIGHTS[0], normal=[0, -1, 0], size=[1.0, 1.0], samples=n)

    scene16 = base.replace(lights=(rect(16),))
    start = time.perf_counter()
    backend = scene_backend(scene16)
    build = time.perf_counter() - start
    load_before = os.getloadavg()
    with Renderer(base) as r:
        fns = {}
        for n in SAMPLES:
            lights = (rect(n),)
            fns[f"rect N={n}"] = lambda lights=lights: r.render(lights=lights)
        for k in (1, 4):
            lights = tuple(PointLight(p) for p in POINT_LIGHTS[:k])
            fns[f"{k} point lights"] = lambda lights=lights: r.render(lights=lights)
        fns[RAY] = lambda: lit_counts(scene16, backend)
        # one renderer for every variant: its kept volumes (CpuVolumes) hold every variant's
        # lights, as for a stream of frames of one setup; counted, so a miss would show
        vols, builds = r.volumes("cpu"), []
        build_volumes = vols._build
        vols._build = lambda light4: builds.append(times_so_far[-1]) or build_volumes(light4)
        times_so_far: list = []
        times = interleaved(fns, args.rounds, times_so_far)
        rebuilt = sum(1 for rnd in builds if rnd > 0)
    load_after = os.getloadavg()
    ms = {name: [t * 1e3 for t in ts] for name, ts in times.items()}
    rounds = range(args.rounds)
    per_sample = [(ms["rect N=16"][i] - ms["rect N=1"][i]) / 15 for i in rounds]
    per_light = [(ms["4 point lights"][i] - ms["1 point lights"][i]) / 3 for i in rounds]
    speedup = [ms[RAY][i] / ms["rect N=16"][i] for i in rounds]

    print(f"{base.name}, {triangle_count(base):,} triangles, {args.width}x{args.height}, "
          f"{args.rounds} rounds interleaved, {os.cpu_count()} cores; load average "
          f"{load_before[0]:.1f} before, {load_after[0]:.1f} after")
    print()
    print("| what | wall time (ms), median (min-max) |")
    print("|---|---:|")
    for what, values in ms.items():
        print(f"| {what if what == RAY else 'raster frame, ' + what} | {spread(values)} |")
    print(f"| Embree BVH build (once per scene) | {build * 1e3:.0f} |")
    print()
    print(f"side quads built in the timed rounds: {rebuilt} (the warm-up round built "
          f"{len(builds) - rebuilt})")
    print()
    n1 = statistics.median(ms["rect N=1"])
    print("growth with N (raster, medians): " + ", ".join(
        f"N={n} {statistics.median(ms[f'rect N={n}']) / n1:.2f}x" for n in SAMPLES)
        + " of N=1")
    print()
    print(f"one further sample: {statistics.median(per_sample):.1f} ms; one further point light: "
          f"{statistics.median(per_light):.1f} ms (target: sample <= point light; per round "
          f"{min(per_sample):.1f}-{max(per_sample):.1f} and "
          f"{min(per_light):.1f}-{max(per_light):.1f} ms)")
    print(f"ray tracer / raster at N=16: {statistics.median(speedup):.2f}x (target >= 3x; per "
          f"round {min(speedup):.2f}-{max(speedup):.2f}x)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
