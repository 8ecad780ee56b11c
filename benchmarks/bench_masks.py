"""Benchmark (not a test): reference masks of the Stanford bunny on a plane against raw Embree.

    python -m benchmarks.bench_masks [--runs N] [--width W] [--height H] [--model OBJ]

The scene: the shared bunny (../shared/models/bunny.obj, 69k triangles, open base), scaled to
about 1.5 units tall, standing on a 6 x 6 plane, one point light, 1280x720.  It times

1. `raytrace.shadow_masks` on a prebuilt Embree backend (the BVH build is reported apart),
2. raw embreex casts of the very same rays: the primary rays (INTERSECT) and the shadow rays
   (OCCLUDED, bounded by the light) that the masks traced, with the same split over threads, in
   float32 arrays prepared before the clock starts;

each as the median of several runs after a warm-up, and prints a markdown table.  Mrays/s counts
primary + shadow rays (shadow rays are cast only where n·l > 0).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
# ../shared/models beside the checkout (or beside its parent)
BUNNY = next((b / "shared" / "models" / "bunny.obj" for b in (ROOT.parent, ROOT.parent.parent)
              if (b / "shared" / "models" / "bunny.obj").is_file()),
             ROOT.parent / "shared" / "models" / "bunny.obj")


def bunny_scene(width: int, height: int, model: Path = BUNNY):
    import trimesh

    from shadowvol import Camera, Material, PointLight, Scene
    from shadowvol.primitives import Transform, mesh, plane

    loaded = trimesh.load(str(model), process=False)
    v = np.asarray(loaded.vertices)
    scale = 1.5 / float(np.ptp(v[:, 1]))
    base = v.min(axis=0) * scale
    centre = (v.max(axis=0) + v.min(axis=0)) / 2 * scale
    bunny = mesh("bunny", v, np.asarray(loaded.faces),
                 Material(diffuse=[0.8, 0.7, 0.6]),
                 Transform(scale=scale, translation=[-centre[0], -base[1], -centre[2]]))
    return Scene(camera=Camera(eye=[0.8, 1.6, 3.6], target=[0.0, 0.65, 0.0], fov_y=40.0),
                 objects=(plane("floor", size=[6.0, 6.0]), bunny),
                 lights=(PointLight([-2.0, 4.0, 2.5]),), width=width, height=height,
                 name="bunny")


def run_times(fns: list, runs: int) -> list[list[float]]:
    """Wall times (s) of each function over `runs` rounds after one warm-up round.  The
    functions take turns within each round, so a noisy neighbour on the machine hurts all
    of them alike."""
    times = [[] for _ in fns]
    for r in range(runs + 1):
        for fn, ts in zip(fns, times):
            t0 = time.perf_counter()
            fn()
            if r:
                ts.append(time.perf_counter() - t0)
    return times


def median_times(fns: list, runs: int) -> list[float]:
    """The median of each function's `run_times`."""
    return [statistics.median(ts) for ts in run_times(fns, runs)]


def _shadow_rays(scene, backend, o, d):
    """The masks' shadow rays of light 0, rebuilt as `measure` says, from the primary rays
    o, d (n, 3) float32: idx (the covered rays' indices), cand (those facing the light, a mask
    over idx), start (m, 3) and shadow_dir (m, 3), dist (m,) float32 or None (unbounded)."""
    from raytrace.tolerances import (
        error_weight,
        light_margin,
        shadow_height,
        through_light,
    )
    from shadowvol import DirectionalLight

    tracer, origin = backend.tracer, backend.origin
    hits = tracer.closest_hit(o.astype(np.float64), d.astype(np.float64))
    idx = np.flatnonzero(hits.tri >= 0)
    point = o[idx] + hits.t[idx, None] * d[idx]
    n = tracer.normals[hits.tri[idx]]
    n *= np.where(np.einsum("ij,ij->i", n, d[idx]) > 0, -1.0, 1.0)[:, None]
    k = hits.tri[idx]
    weight = error_weight(tracer.normals, tracer.vertices[tracer.faces])
    height = shadow_height(weight[k] + np.einsum("ij,ij->i", np.abs(tracer.normals[k]),
                                                 np.abs(point)))
    light = scene.lights[0]
    if isinstance(light, DirectionalLight):  # unbounded rays along -direction
        toward = np.broadcast_to(-light.direction, point.shape)
        n_dot_l = np.einsum("ij,ij->i", n, toward)
        cand = n_dot_l > 0
        start = point[cand] + (height[cand] / n_dot_l[cand])[:, None] * toward[cand]
        shadow_dir, dist = np.broadcast_to(-light.direction, start.shape), None
    else:                                    # the segment to the light, tmax < 1
        position = light.position - origin
        toward = position - point
        n_dot_l = np.einsum("ij,ij->i", n, toward)
        cand = n_dot_l > 0
        near = height[cand] / n_dot_l[cand]
        length = np.linalg.norm(toward[cand], axis=1)
        start = point[cand] + near[:, None] * toward[cand]
        shadow_dir = toward[cand]
        through = through_light(tracer.normals, tracer.plane_d, weight, position)
        dist = (1.0 - light_margin(position, length, through) / length
                - near).astype(np.float32)
    return idx, cand, start, shadow_dir, dist


def measure(scene, runs: int, full: bool = True) -> dict:
    """Time `raytrace.shadow_masks(scene)` on a prebuilt Embree backend against raw embreex
    casts of the very same rays (light 0: a point or directional light), interleaved.

    Returns a dict: triangles, threads, primary_rays, shadow_rays, coverage, lit (fractions),
    mismatched (pixels where the raw rays' verdict differs from the masks), build_s, and
    masks / raw / full (incl. the BVH build; only if `full`) as {"median", "min", "max"} in
    seconds."""
    from raytrace import shadow_masks
    from raytrace.camera import primary_rays
    from raytrace.masks import scene_backend

    vertices, faces, _ = scene.triangles()
    t0 = time.perf_counter()
    backend = scene_backend(scene, "embree")
    build = time.perf_counter() - t0
    lit, coverage = shadow_masks(scene, backend)
    tracer = backend.tracer

    # The same rays, rebuilt outside the clock as float32 arrays ready for embreex, the way
    # raytrace.masks builds them, in the backend's frame (origin at the eye): primary rays
    # through the pixel centres from the near plane; wherever n·l > 0, the segment from the hit
    # point to the light shortened at the surface by shadow_height / (n·l) and before a point
    # light by light_margin (computed here in float64).  The masks' second casts (a blocked ray
    # whose blocker may be its own triangle) are not among the raw rays: their cost shows.
    origin = backend.origin
    camera = scene.camera.__class__(eye=scene.camera.eye - origin,
                                    target=scene.camera.target - origin, up=scene.camera.up,
                                    fov_y=scene.camera.fov_y, near=scene.camera.near)
    o, d = primary_rays(camera, scene.width, scene.height, dtype=np.float32, unit=False)
    idx, cand, start, shadow_dir, dist = _shadow_rays(scene, backend, o, d)
    raw = {
        "INTERSECT": (o, d, None),
        "OCCLUDED": (start.astype(np.float32),
                     np.ascontiguousarray(shadow_dir, dtype=np.float32), dist),
    }
    # Sanity: these rays give the same masks (up to float32-vs-float64 decisions of n·l > 0).
    # The raw casts are embreex's (one rtcIntersect1/rtcOccluded1 a ray), whichever Embree
    # queries the masks' backend runs (`raytrace.embree`: packets by default).
    from raytrace.embree import EmbreeBackend
    single = tracer if isinstance(tracer, EmbreeBackend) else EmbreeBackend(tracer.vertices,
                                                                            tracer.faces)
    raw_lit = np.zeros(len(o), bool)
    raw_lit[idx[cand]] = single._scene.run(*raw["OCCLUDED"], query="OCCLUDED") == -1
    mismatched = int((raw_lit.reshape(lit.shape[1:]) != lit[0]).sum())
    emb = single._scene
    threads = tracer.threads
    one_light = scene.replace(lights=scene.lights[:1])

    def raw_casts():
        with ThreadPoolExecutor(threads) as pool:
            for query, (ro, rd, dd) in raw.items():
                b = np.linspace(0, len(ro), threads + 1).astype(int)
                list(pool.map(lambda s: emb.run(ro[s], rd[s], dists=dd, query=query),
                              [slice(x, y) for x, y in zip(b[:-1], b[1:])]))

    fns = [lambda: shadow_masks(one_light, backend), raw_casts]
    if full:
        fns.append(lambda: shadow_masks(one_light, "embree"))
    times = run_times(fns, runs)
    stats = [{"median": statistics.median(t), "min": min(t), "max": max(t)} for t in times]
    out = {"triangles": len(faces), "threads": threads, "primary_rays": len(o),
           "shadow_rays": len(start), "coverage": float(coverage.mean()),
           "lit": float(lit[0].mean()), "mismatched": mismatched, "build_s": build,
           "masks": stats[0], "raw": stats[1], "runs": runs}
    if full:
        out["full"] = stats[2]
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=7, help="timed runs after one warm-up (median)")
    ap.add_argument("--width", type=int, default=1280)
    ap.add_argument("--height", type=int, default=720)
    ap.add_argument("--model", type=Path, default=BUNNY,
                    help=f"the bunny OBJ (default: {BUNNY})")
    args = ap.parse_args(argv)
    if not args.model.is_file():
        print(f"error: the Stanford bunny is missing: {args.model} does not exist.  This "
              "benchmark needs the shared models folder (../shared/models/bunny.obj beside the "
              "checkout) or --model PATH.", file=sys.stderr)
        return 2

    r = measure(bunny_scene(args.width, args.height, args.model), args.runs)
    print(f"bunny on a plane, {args.width}x{args.height}, {r['triangles']:,} triangles, "
          f"1 point light, {r['threads']} threads; {r['primary_rays']:,} primary + "
          f"{r['shadow_rays']:,} shadow rays; coverage {r['coverage']:.1%}, lit {r['lit']:.1%}; "
          f"medians of {args.runs} runs; the raw rays reproduce the masks but for "
          f"{r['mismatched']} pixels")
    print()
    print("| what | wall time (ms) | Mrays/s |")
    print("|---|---:|---:|")
    print(f"| Embree BVH build (once per scene) | {r['build_s'] * 1e3:.0f} | |")
    n_rays = r['primary_rays'] + r['shadow_rays']
    for what, key in [("`shadow_masks` (prebuilt backend)", "masks"),
                      ("raw embreex casts of the same rays", "raw"),
                      ("`shadow_masks(scene)` incl. build", "full")]:
        t = r[key]["median"]
        print(f"| {what} | {t * 1e3:.0f} | {n_rays / t / 1e6:.1f} |")
    print()
    print(f"masks / raw throughput: {r['raw']['median'] / r['masks']['median']:.2f}x "
          f"(target >= 0.8x)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
