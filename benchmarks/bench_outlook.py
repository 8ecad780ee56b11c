"""Benchmark (not a test): path tracing and radiosity on the Cornell box (issue 15's targets).

    python -m benchmarks.bench_outlook [--size 512] [--spp 4] [--runs 3] [--json PATH]

1. Path tracing throughput: `raytrace.outlook.path.pathtrace.render` of scenes/cornell.toml at size
   x size, Mrays/s counting every ray it traced (camera, bounce and shadow rays), against two raw
   embreex baselines, each on as many threads as the path tracer uses (`cpu_threads()`):
   * `raw`: the same number of closest-hit rays, random origins inside the box and random
     directions, float32 arrays prepared before the clock, one chunk per thread on a thread
     pool as `raytrace.backends` does (the issue's "raw Embree casts"; target: path tracing
     >= 0.6x raw);
   * `replay`: the very rays the path tracer cast (recorded in an untimed render of the same
     seed: camera and bounce rays as closest-hit queries, shadow rays as bounded occlusion
     queries, in the same batches, float32 as Embree gets them), each thread replaying the
     batches one of the path tracer's tile threads cast, on a pool of the same size: the path
     tracer's time with its shading made free.
   Both per-bounce shadings of the path tracer (`raytrace.outlook.path.pathtrace.shading`: numpy,
   and numba where it imports) are timed; the top-level figures, and the target, are the default
   one's (numba when installed; `by_shading` has both, and whether their images are identical), and
   `numba_compile_seconds` the first numba render's time with a cold and a warm cache. All are
   interleaved round by round (path trace numpy, numba, raw, replay), medians reported, in wall time
   and in this process's CPU time (`time.process_time`, all threads): other sessions on the same
   cores stretch wall times unevenly (a thread pool waits for its slowest thread), CPU times much
   less, so `cpu_ratio_to_raw` is the steadier figure under load; on an idle machine the two ratios
   agree when both sides keep the cores equally busy.
2. Radiosity time (meshing, form factors, solve, as `raytrace radiosity` runs it) at about 1k,
   4k and 16k triangles (each triangle is two patches, one per face).

`measure()` returns the numbers as a dict; run as a script it prints them as JSON.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CORNELL = ROOT / "scenes" / "cornell.toml"
PATCH_TARGETS = (1000, 4000, 16000)  # triangles


def raw_embree_seconds(scene, n_rays: int, runs: int, cpu: list | None = None) -> float:
    """Median seconds for embreex to trace n_rays closest-hit rays inside the scene's box
    (with cpu, a list: each run's CPU seconds are appended to it)."""
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
            t, c = time.perf_counter(), time.process_time()
            list(pool.map(lambda s: es.run(o[s], d[s]), parts))
            times.append(time.perf_counter() - t)
            if cpu is not None:
                cpu.append(time.process_time() - c)
    return statistics.median(times)


def _recorded_batches(scene, spp: int, seed: int) -> list[list[tuple]]:
    """The Embree queries of one path-traced render, per thread that cast them, in order:
    (query, origins (n, 3) float32, directions (n, 3) float32, tfar or None)."""
    from raytrace.outlook.path import pathtrace

    per_thread: dict[int, list[tuple]] = {}

    class Recording(pathtrace.PathWorld):
        def _log(self, query, o, d, tmax):
            per_thread.setdefault(threading.get_ident(), []).append(
                (query, np.ascontiguousarray(o.T, np.float32),
                 np.ascontiguousarray(d.T, np.float32), tmax))

        def closest_rows(self, o, d):
            self._log("INTERSECT", o, d, None)
            return super().closest_rows(o, d)

        def occluded_rows(self, o, d, tmax):
            self._log("OCCLUDED", o, d, tmax)
            return super().occluded_rows(o, d, tmax)

    original, pathtrace.PathWorld = pathtrace.PathWorld, Recording
    try:
        pathtrace.render(scene, spp=spp, seed=seed, progress=False)
    finally:
        pathtrace.PathWorld = original
    return list(per_thread.values())


def replay_seconds(es, batches: list[list[tuple]]) -> tuple[float, float]:
    """Wall and CPU seconds for embreex scene `es` to cast the recorded batches, one thread per
    list."""
    def cast(queue):
        for query, o, d, tmax in queue:
            es.run(o, d, dists=tmax, query=query)

    with ThreadPoolExecutor(len(batches)) as pool:
        t, c = time.perf_counter(), time.process_time()
        list(pool.map(cast, batches))
        return time.perf_counter() - t, time.process_time() - c


def compile_seconds() -> dict:
    """Seconds of the first numba-shaded render of a 16x16 Cornell box in a fresh process with
    an empty numba cache (`cold`: every kernel compiled) and again in a second process with the
    cache it left (`cached`: loaded from disk), each with the process's imports excluded; the
    numpy-shaded render of the same size in the second process for scale (`numpy`)."""
    import subprocess
    import tempfile

    code = ("import sys, time; "
            "from raytrace.outlook.path.pathtrace import render; from shadowvol import load_scene; "
            "s = load_scene(sys.argv[1]).replace(width=16, height=16); out = []\n"
            "for name in ('numba', 'numpy'):\n"
            "    t = time.perf_counter(); render(s, spp=1, shading_name=name, progress=False)\n"
            "    out.append(time.perf_counter() - t)\n"
            "print(out[0], out[1])")
    times = []
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        for _ in range(2):
            done = subprocess.run([sys.executable, "-c", code, str(CORNELL)],
                                  cwd=ROOT, env=env, capture_output=True, text=True, check=True)
            times.append([float(x) for x in done.stdout.split()])
    return {"cold": times[0][0], "cached": times[1][0], "numpy": times[1][1]}


def path_tracing(size: int, spp: int, runs: int) -> dict:
    """Both shadings (numpy, numba where it imports) interleaved with the raw and replayed
    Embree casts, round by round; the top-level figures are the default shading's."""
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    from raytrace.backends import cpu_threads
    from raytrace.outlook.path.pathtrace import render, shading
    from shadowvol import load_scene

    default = shading()
    shadings = ["numpy"] + (["numba"] if shading("auto") == "numba" else [])
    scene = load_scene(CORNELL).replace(width=size, height=size)
    for name in shadings:  # warm-up (imports, the first BVH, numba's compile or cache load)
        render(scene.replace(width=16, height=16), spp=1, shading_name=name, progress=False)
    vertices, faces, _ = scene.triangles()
    es = rtcore_scene.EmbreeScene()
    TriangleMesh(es, vertices.astype(np.float32), faces.astype(np.int32))
    es.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32))  # the BVH
    results = {name: [] for name in shadings}
    cpu = {name: [] for name in shadings}
    raw, raw_cpu, replay, replay_cpu = [], [], [], []
    for i in range(runs):
        for name in shadings:
            c = time.process_time()
            results[name].append(render(scene, spp=spp, seed=i, shading_name=name,
                                        progress=False))
            cpu[name].append(time.process_time() - c)
        rays = results[shadings[0]][-1].rays
        raw.append(raw_embree_seconds(scene, rays, 1, cpu=raw_cpu))
        batches = _recorded_batches(scene, spp, seed=i)
        wall, c = replay_seconds(es, batches)
        replay.append(wall)
        replay_cpu.append(c)
        del batches
    raw_s, replay_s = statistics.median(raw), statistics.median(replay)
    raw_cpu_s, replay_cpu_s = statistics.median(raw_cpu), statistics.median(replay_cpu)
    by_shading = {}
    for name in shadings:
        rs = results[name]
        seconds = statistics.median(r.seconds for r in rs)
        cpu_s = statistics.median(cpu[name])
        rays = int(statistics.median(r.rays for r in rs))
        by_shading[name] = {
            "rays": rays, "seconds": seconds,
            "seconds_min_max": [min(r.seconds for r in rs), max(r.seconds for r in rs)],
            "mrays_per_s": rays / seconds / 1e6, "ratio_to_raw": raw_s / seconds,
            "ratio_to_raw_min_max": [min(raw) / max(r.seconds for r in rs),
                                     max(raw) / min(r.seconds for r in rs)],
            "ratio_to_replay": replay_s / seconds, "cpu_seconds": cpu_s,
            "cpu_ratio_to_raw": raw_cpu_s / cpu_s, "cpu_ratio_to_replay": replay_cpu_s / cpu_s}
    same = all(np.array_equal(a.image, b.image) for a, b in
               zip(results["numpy"], results.get("numba", results["numpy"])))
    top = by_shading[default]
    return {"size": size, "spp": spp, "threads": cpu_threads(), "shading": default,
            **{key: top[key] for key in ("rays", "seconds", "seconds_min_max", "mrays_per_s")},
            "raw_embree_seconds": raw_s, "raw_embree_mrays_per_s": top["rays"] / raw_s / 1e6,
            "ratio_to_raw": top["ratio_to_raw"],
            "replay_embree_seconds": replay_s,
            "replay_embree_mrays_per_s": top["rays"] / replay_s / 1e6,
            "ratio_to_replay": top["ratio_to_replay"], "target_ratio": 0.6,
            "target_met": top["ratio_to_raw"] >= 0.6,
            "cpu_seconds": top["cpu_seconds"], "raw_embree_cpu_seconds": raw_cpu_s,
            "replay_embree_cpu_seconds": replay_cpu_s,
            "cpu_ratio_to_raw": top["cpu_ratio_to_raw"],
            "cpu_ratio_to_replay": top["cpu_ratio_to_replay"],
            "by_shading": by_shading, "images_identical_across_shadings": same,
            "numba_compile_seconds": compile_seconds() if "numba" in shadings else None,
            "load_average": list(os.getloadavg())}


def radiosity_times(targets=PATCH_TARGETS, rays_per_patch: int = 256) -> list[dict]:
    from raytrace.outlook import radiosity
    from shadowvol import load_scene

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


def measure(size: int = 512, spp: int = 4, runs: int = 3, radiosity: bool = True) -> dict:
    """Both benchmarks: {"path_tracing": {...}, "radiosity": [{...} per size]}."""
    return {"path_tracing": path_tracing(size, spp, runs),
            "radiosity": radiosity_times() if radiosity else None}


def report(r: dict) -> list[str]:
    """The lines the run prints (short: BENCHMARKS.md keeps them verbatim; --json has all)."""
    p = r["path_tracing"]
    lines = [f"path tracing {p['size']}x{p['size']}, {p['spp']} spp, {p['threads']} threads, "
             f"{p['rays']:,} rays; load {p['load_average'][0]:.1f}",
             "| shading | s (median) | Mrays/s | / raw Embree (wall, CPU) "
             "| / replayed Embree (wall, CPU) |", "|---|---:|---:|---|---|"]
    for name, v in p["by_shading"].items():
        lines.append(f"| {name} | {v['seconds']:.3f} | {v['mrays_per_s']:.1f} | "
                     f"{v['ratio_to_raw']:.2f}, {v['cpu_ratio_to_raw']:.2f} | "
                     f"{v['ratio_to_replay']:.2f}, {v['cpu_ratio_to_replay']:.2f} |")
    lines.append(f"raw Embree {p['raw_embree_mrays_per_s']:.1f} Mrays/s, replayed "
                 f"{p['replay_embree_mrays_per_s']:.1f}; target ratio to raw "
                 f">= {p['target_ratio']}: {'met' if p['target_met'] else 'NOT met'}; images "
                 f"identical across shadings: {p['images_identical_across_shadings']}; numba "
                 "compile s: " + ", ".join(f"{k} {v:.2f}" for k, v in
                                          p["numba_compile_seconds"].items()))
    if r.get("radiosity"):
        lines += ["| radiosity triangles | patches | rays/patch | form factors s | solve s "
                  "| iterations | total s |", "|---:|---:|---:|---:|---:|---:|---:|"]
        lines += [f"| {x['triangles']:,} | {x['patches']:,} | {x['rays_per_patch']} | "
                  f"{x['form_factor_s']:.2f} | {x['solve_s']:.2f} | {x['iterations']:,} | "
                  f"{x['total_s']:.2f} |" for x in r["radiosity"]]
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--spp", type=int, default=4)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--no-radiosity", action="store_true", help="path tracing only")
    ap.add_argument("--json", type=Path, help="also write every number here")
    args = ap.parse_args(argv)
    r = measure(args.size, args.spp, args.runs, not args.no_radiosity)
    print("\n".join(report(r)))
    if args.json:
        args.json.write_text(json.dumps(r, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
