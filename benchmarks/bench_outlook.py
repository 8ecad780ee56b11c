"""Benchmark (not a test): path tracing and radiosity on the Cornell box (issue 15's targets).

    python benchmarks/bench_outlook.py [--size 512] [--spp 4] [--runs 3]

1. Path tracing throughput: `raytrace.pathtrace.render` of scenes/cornell.toml at size x size,
   Mrays/s counting every ray it traced (camera, bounce and shadow rays), against raw embreex
   casts of the same number of rays (closest hit, random origins inside the box and random
   directions, float32 arrays prepared before the clock, one chunk per core on a thread pool as
   `raytrace.backends` does).  Target: path tracing >= 0.6x raw.
2. Radiosity time (meshing, form factors, solve, as `raytrace radiosity` runs it) at about 1k,
   4k and 16k triangles (each triangle is two patches, one per face).

`measure()` returns the numbers as a dict; run as a script it prints them as JSON.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run from a checkout, installed or not
CORNELL = ROOT / "scenes" / "cornell.toml"
PATCH_TARGETS = (1000, 4000, 16000)  # triangles


def raw_embree_seconds(scene, n_rays: int, runs: int) -> float:
    """Median seconds for embreex to trace n_rays closest-hit rays inside the scene's box."""
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    from raytrace.backends import MIN_RAYS_PER_THREAD, cpu_threads

    vertices, faces, _ = scene.triangles()
    es = rtcore_scene.EmbreeScene()
    TriangleMesh(es, vertices.astype(np.float32), faces.astype(np.int32))
    rng = np.random.default_rng(0)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    o = (lo + (hi - lo) * rng.random((n_rays, 3))).astype(np.float32)
    d = rng.normal(size=(n_rays, 3))
    d = (d / np.linalg.norm(d, axis=1)[:, None]).astype(np.float32)
    threads = min(cpu_threads(), max(1, n_rays // MIN_RAYS_PER_THREAD))
    bounds = np.linspace(0, n_rays, threads + 1).astype(int)
    parts = [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:])]
    es.run(o[:1], d[:1])  # build the BVH before the clock
    times = []
    with ThreadPoolExecutor(threads) as pool:
        for _ in range(runs):
            t = time.perf_counter()
            list(pool.map(lambda s: es.run(o[s], d[s]), parts))
            times.append(time.perf_counter() - t)
    return statistics.median(times)


def path_tracing(size: int, spp: int, runs: int) -> dict:
    from raytrace.pathtrace import render
    from shadowvol.scenefile import load_scene

    scene = load_scene(CORNELL).replace(width=size, height=size)
    render(scene.replace(width=16, height=16), spp=1)  # warm-up (imports, first BVH)
    results = [render(scene, spp=spp, seed=i, progress=False) for i in range(runs)]
    seconds = statistics.median(r.seconds for r in results)
    rays = int(statistics.median(r.rays for r in results))
    raw = raw_embree_seconds(scene, rays, runs)
    return {"size": size, "spp": spp, "rays": rays, "seconds": seconds,
            "mrays_per_s": rays / seconds / 1e6, "raw_embree_seconds": raw,
            "raw_embree_mrays_per_s": rays / raw / 1e6, "ratio_to_raw": raw / seconds,
            "target_ratio": 0.6}


def radiosity_times(targets=PATCH_TARGETS, rays_per_patch: int = 256) -> list[dict]:
    from raytrace import radiosity
    from shadowvol.scenefile import load_scene

    scene = load_scene(CORNELL)
    rows = []
    for target in targets:
        lo, hi = 1.0, 2000.0  # max_edge (mm): bisect to about `target` triangles
        for _ in range(30):
            mid = (lo * hi) ** 0.5
            if radiosity.mesh_patches(scene, max_edge=mid).triangles > target:
                lo = mid
            else:
                hi = mid
        t = time.perf_counter()
        mesh = radiosity.mesh_patches(scene, max_edge=hi)
        sol = radiosity.solve(scene, rays_per_patch=rays_per_patch, shots=16, mesh=mesh)
        total = time.perf_counter() - t
        rows.append({"target_triangles": target, "triangles": mesh.triangles,
                     "patches": mesh.patches, "rays_per_patch": rays_per_patch,
                     "form_factor_s": sol.form_factor_seconds, "solve_s": sol.solve_seconds,
                     "iterations": sol.iterations, "shots": sol.shots,
                     "unshot": sol.unshot, "total_s": total})
    return rows


def measure(size: int = 512, spp: int = 4, runs: int = 3) -> dict:
    """Both benchmarks: {"path_tracing": {...}, "radiosity": [{...} per size]}."""
    return {"path_tracing": path_tracing(size, spp, runs), "radiosity": radiosity_times()}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--spp", type=int, default=4)
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args(argv)
    print(json.dumps(measure(args.size, args.spp, args.runs), indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
