"""Benchmark (not a test): what each extra 64-object word of `casters` costs, in both renderers.

    python -m benchmarks.bench_caster_words [--runs N] [--width W] [--height H]

The same 256 small boxes on a floor under one point light, the scene 64, 128 or 256 objects
(the floor and the boxes split into 63, 127 or 255 runs of consecutive boxes: K = 1, 2 or 4
words), so the triangles, the shadows and the frame are the same and only the object count
differs: the
rasterizer counts one word's candidates at a time (one clear and one read a word, one counting
pass per 32 candidates), the ray tracer traces each blocked segment against each object's own
backend.  Per object count: the frame's milliseconds with and without casters (medians of
interleaved rounds after a warm-up) and the casters' extra cost as a ratio to that at 64.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

COUNTS = (64, 128, 256)
BOXES = 256
FRAME = ("lit", "coverage")


def grouped_scene(objects: int, width: int, height: int):
    """The floor and BOXES boxes (a 16 x 16 grid, every other one taller) as `objects`
    objects: the floor and objects - 1 runs of consecutive boxes, each merged into one mesh."""
    from shadowvol.primitives import box, mesh, plane
    from shadowvol.scene import Camera, PointLight, Scene

    boxes = []
    for k in range(BOXES):
        x, z = k % 16, k // 16
        tall = 0.5 if (x + z) % 2 else 0.25
        boxes.append(box(f"b{k}", [0.3 * x - 2.25, tall / 2, 0.3 * z - 2.25],
                         [0.15, tall, 0.15]))
    merged = []
    for g, parts in enumerate(np.array_split(np.arange(BOXES), objects - 1)):
        parts = [boxes[k] for k in parts]
        offsets = np.cumsum([0] + [len(p.vertices) for p in parts[:-1]])
        merged.append(mesh(f"group{g}", np.concatenate([p.vertices for p in parts]),
                           np.concatenate([p.faces + o for p, o in zip(parts, offsets)])))
    return Scene(camera=Camera(eye=[0.0, 6.0, 4.0], target=[0.0, 0.0, 0.0], fov_y=50.0),
                 objects=[plane("floor", size=[7, 7])] + merged,
                 lights=[PointLight([0.6, 3.5, 0.8])], width=width, height=height)


def _median_ms(fn, runs: int) -> float:
    fn()
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return 1e3 * statistics.median(times)


def measure(ctx, runs: int = 5, width: int = 640, height: int = 480) -> dict:
    """{"raster": {n: {...}}, "raytrace": {n: {...}}}: per object count n the frame, the frame
    with casters (ms), the casters' extra ms and its ratio to that at 64 objects."""
    import raytrace
    from raytrace.masks import scene_backend
    from shadowvol import Renderer
    from shadowvol.frame import caster_words

    out: dict = {"raster": {}, "raytrace": {}}
    for n in COUNTS:
        scene = grouped_scene(n, width, height)
        with Renderer(scene, ctx) as r:
            frame = _median_ms(lambda: r.render(outputs=FRAME), runs)
            casters = _median_ms(lambda: r.render(outputs=FRAME + ("casters",)), runs)
        out["raster"][n] = {"words": caster_words(n), "frame": frame, "casters": casters}
        backend = scene_backend(scene, "embree")
        frame = _median_ms(lambda: raytrace.ground_truth(scene, (), backend), max(2, runs // 2))
        casters = _median_ms(lambda: raytrace.ground_truth(scene, ("casters",), backend),
                             max(2, runs // 2))
        out["raytrace"][n] = {"words": caster_words(n), "frame": frame, "casters": casters}
    for rows in out.values():
        base = rows[COUNTS[0]]["casters"] - rows[COUNTS[0]]["frame"]
        for row in rows.values():
            row["extra"] = row["casters"] - row["frame"]
            row["ratio_to_64"] = row["extra"] / base if base > 0 else float("nan")
    return out


def report(result: dict) -> list[str]:
    lines = ["| renderer | objects | words K | frame ms | + casters ms | extra ms | extra / "
             "extra at 64 |", "|---|---|---|---|---|---|---|"]
    for who, rows in result.items():
        for n, r in rows.items():
            lines.append(f"| {who} | {n} | {r['words']} | {r['frame']:.1f} | "
                         f"{r['casters']:.1f} | {r['extra']:.1f} | {r['ratio_to_64']:.2f} |")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--width", type=int, default=640)
    ap.add_argument("--height", type=int, default=480)
    args = ap.parse_args(argv)
    from shadowvol.raster.platform.context import create_context

    ctx = create_context()
    try:
        print("\n".join(report(measure(ctx, args.runs, args.width, args.height))))
    finally:
        ctx.release()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
