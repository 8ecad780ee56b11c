"""Benchmark (not a test): ns per ray of Embree's packets against embreex's single rays, on 1
and 2 threads.

    python -m benchmarks.bench_packets [--runs 5] [--json FILE]

The rays: the 1280x720 pixel-centre primary rays of the bunny scene (`bench_masks.bunny_scene`,
69k triangles on a floor; without ../shared/models the 100k procedural scene stands in, and the
output says so), closest hits (`closest_triangle`), and from each hit, lifted 1e-4 of the scene
along its camera-facing normal, one bounded occlusion ray to the point light (`occluded`), as
float32 arrays prepared before the clock.  Each backend (`raytrace.embree.EmbreeBackend`: one
`rtcIntersect1`/`rtcOccluded1` per ray, chunks on a thread pool; `PacketBackend`: packets of
the CPU's width on numba's threads) answers the same rays, the answers checked equal, at 1 and
at 2 threads; the variants take turns round by round, medians.  Wall ns per ray, and CPU ns
per ray (all threads: the cost of a ray on one core).
"""

from __future__ import annotations

import statistics
import sys
import time

import numpy as np

from . import scenes
from .cli import bench_main, load_span
from .bench_masks import BUNNY, bunny_scene


def bench_scene():
    if scenes.models_dir() is None or not BUNNY.is_file():
        return scenes.occluder_scene("100k", 1, 1280, 720), False
    return bunny_scene(1280, 720), True


def rays(scene):
    """(primary origins, directions), (shadow origins, directions, tmax): float32 rows."""
    from raytrace.camera import RayGrid
    from raytrace.embree import EmbreeBackend
    vertices, faces, _ = scene.triangles()
    grid = RayGrid(scene.camera, scene.width, scene.height, np.float32)
    d = grid.directions()
    o = np.ascontiguousarray(grid.origins(d).T)
    d = np.ascontiguousarray(d.T)
    tracer = EmbreeBackend(vertices, faces)
    hit = tracer.closest_hit(o, d)
    k = np.flatnonzero(hit.tri >= 0)
    n = tracer.normals[hit.tri[k]].astype(np.float32)
    n *= np.where((n * d[k]).sum(axis=1) > 0, -1.0, 1.0)[:, None].astype(np.float32)
    start = o[k] + hit.t[k, None] * d[k] + np.float32(1e-4 * scene.extent) * n
    to = scene.lights[0].position.astype(np.float32) - start
    return (o, d), (np.ascontiguousarray(start), np.ascontiguousarray(to),
                    np.full(len(start), 0.999, np.float32))


def measure(runs: int) -> dict:
    import numba

    from raytrace.embree import EmbreeBackend, PacketBackend
    scene, shared = bench_scene()
    vertices, faces, _ = scene.triangles()
    (po, pd), (so, sd, st) = rays(scene)
    backends = {"single": EmbreeBackend(vertices, faces), "packets": PacketBackend(vertices, faces)}
    queries = {"primary (closest hit)": lambda b: b.closest_triangle(po, pd),
               "shadow (occluded)": lambda b: b.occluded(so, sd, st)}
    counts = {"primary (closest hit)": len(po), "shadow (occluded)": len(so)}
    for q, fn in queries.items():   # warm-up (numba's compile) and the answers checked equal
        assert np.array_equal(fn(backends["single"]), fn(backends["packets"])), q
    samples: dict = {}
    for _ in range(runs):
        for threads in (1, 2):
            numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
            for name, b in backends.items():
                b.threads = threads
                for q, fn in queries.items():
                    w, c = time.perf_counter(), time.process_time()
                    fn(b)
                    s = samples.setdefault((q, name, threads), {"wall": [], "cpu": []})
                    s["wall"].append((time.perf_counter() - w) * 1e9 / counts[q])
                    s["cpu"].append((time.process_time() - c) * 1e9 / counts[q])
    rows = [{"rays": q, "backend": name, "threads": t, "rays_n": counts[q],
             "wall_ns": statistics.median(s["wall"]), "cpu_ns": statistics.median(s["cpu"])}
            for (q, name, t), s in samples.items()]
    return {"scene": scene.name, "shared_meshes": shared,
            "triangles": sum(len(o.faces) for o in scene.objects), "runs": runs, "rows": rows}


def table(result: dict) -> str:
    rows = {(r["rays"], r["backend"], r["threads"]): r for r in result["rows"]}
    lines = ["| rays | threads | single wall / CPU ns | packets wall / CPU ns | "
             "single / packets (wall) |", "|---|---:|---:|---:|---:|"]
    for q in dict.fromkeys(r["rays"] for r in result["rows"]):
        for t in (1, 2):
            s, p = rows[(q, "single", t)], rows[(q, "packets", t)]
            lines.append(f"| {q}, {s['rays_n']:,} | {t} | {s['wall_ns']:.0f} / {s['cpu_ns']:.0f}"
                         f" | {p['wall_ns']:.0f} / {p['cpu_ns']:.0f} | "
                         f"{s['wall_ns'] / p['wall_ns']:.2f}x |")
        for b in ("single", "packets"):
            lines.append(f"| {q}: {b}, 1 -> 2 threads | | | | "
                         f"{rows[(q, b, 1)]['wall_ns'] / rows[(q, b, 2)]['wall_ns']:.2f}x |")
    return "\n".join(lines)


def main(argv=None) -> int:
    def report(result: dict, args) -> str:
        missing = "" if result["shared_meshes"] else " (../shared/models not found)"
        return (f"{result['scene']}, {result['triangles']:,} triangles{missing}, "
                f"{args.runs} rounds; {load_span(result)}\n{table(result)}")

    return bench_main(argv, "bench_packets", __doc__, lambda a: measure(a.runs), report)


if __name__ == "__main__":
    sys.exit(main())
