"""Benchmark (not a test): what each ground-truth output of the ray tracer costs on a
100k-triangle frame.

    python benchmarks/bench_groundtruth.py [--runs N] [--width W] [--height H] [--lights N]

The scene: the benchmark's `occluder_scene("100k")` (a floor and 20 icospheres, 102,402
triangles, 21 objects), 1280x720, point lights.  On one prebuilt Embree backend it times
`raytrace.shadow_masks`, then `raytrace.ground_truth` with no output, each output alone, and all
of them, as the median of several runs after a warm-up, and prints a markdown table (seconds and
the ratio to the masks).
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


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--width", type=int, default=1280)
    ap.add_argument("--height", type=int, default=720)
    ap.add_argument("--lights", type=int, default=1)
    args = ap.parse_args(argv)

    from scenes import occluder_scene

    import raytrace
    from raytrace.masks import scene_backend
    from shadowvol.io import GROUND_TRUTH

    scene = occluder_scene("100k", args.lights, args.width, args.height)
    backend = scene_backend(scene, "embree")

    def median(fn) -> float:
        fn()  # warm-up
        times = []
        for _ in range(args.runs):
            start = time.perf_counter()
            fn()
            times.append(time.perf_counter() - start)
        return statistics.median(times)

    masks = median(lambda: raytrace.shadow_masks(scene, backend))
    rows = [("shadow_masks (lit, coverage)", masks)]
    rows.append(("ground_truth, no output", median(lambda: raytrace.ground_truth(scene, (),
                                                                               backend))))
    for name in GROUND_TRUTH:
        rows.append((f"ground_truth + {name}",
                     median(lambda: raytrace.ground_truth(scene, [name], backend))))
    rows.append(("ground_truth, all", median(lambda: raytrace.ground_truth(scene, GROUND_TRUTH,
                                                                         backend))))
    triangles = sum(len(o.faces) for o in scene.objects)
    print(f"{scene.name}: {triangles} triangles, {len(scene.objects)} objects, "
          f"{len(scene.lights)} light(s), {args.width}x{args.height}, median of {args.runs}\n")
    print("| call | s | x masks |\n|---|---|---|")
    for label, t in rows:
        print(f"| {label} | {t:.3f} | {t / masks:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
