"""Benchmark (not a test): `shadowvol masks --renderer auto` against the renderer it did not
choose, over scenes of 1k to 1M triangles, 1 to 144 hard lights and 320x240 to 1280x720.

    python -m benchmarks.bench_fastest [--runs 3] [--quick] [--json FILE]

Per scene, the masks the command writes (`shadowvol.compare.fastest.masks`: the rasterizer's
mask-only frame with its Renderer built, the ray tracer with its BVH built, as one command
makes them) by each renderer in turn, round by round after a warm-up, wall ms medians; the
cost model's estimates (`fastest.costs`) and choice (`fastest.choose`); and what the choice
costs against the faster one measured (1.00: it chose the faster), all after a warm-up (the
model's `first=False`: a fresh process's one-off costs are not in these times).  Then the model's
constants fitted again to this run (non-negative least squares), to compare with those in
`shadowvol.compare.fastest`, and the one-off costs of a fresh process's first masks (each
renderer in processes of its own: the first masks of a 32x24 scene less its second).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from . import scenes

ROOT = Path(__file__).resolve().parents[1]


def bench_scenes(quick: bool) -> list:
    """The scenes measured: procedural occluders, the shipped scenes and, where
    ../shared/models is, the bunny and the turntable."""
    from shadowvol.scenefile import load_scene

    if quick:
        return [scenes.occluder_scene("1k", 1, 160, 120),
                load_scene(ROOT / "scenes" / "stack.toml").replace(width=160, height=120)]
    out = [scenes.occluder_scene(size, lights, w, h)
           for size, lights, (w, h) in (("1k", 1, (320, 240)), ("1k", 4, (1280, 720)),
                                        ("10k", 2, (640, 480)), ("100k", 1, (640, 480)),
                                        ("100k", 1, (1280, 720)), ("100k", 4, (1280, 720)),
                                        ("1M", 1, (1280, 720)))]
    out += [load_scene(ROOT / "scenes" / f"{name}.toml")
            for name in ("whitted", "cage", "stack", "soft")]
    if scenes.models_dir() is not None:
        out += [scenes.model_scene("bunny"), scenes.turntable_scene(640, 480)]
    return out


def measure(scene, ctx, runs: int) -> dict:
    from shadowvol.compare import fastest

    order = ("shadowvol", "raytrace")
    for renderer in order:                    # warm-up: imports, shaders, numba, caches
        fastest.masks(scene, renderer, ctx)
    times: dict[str, list[float]] = {r: [] for r in order}
    for k in range(runs):
        for renderer in (order if k % 2 == 0 else order[::-1]):
            start = time.perf_counter()
            fastest.masks(scene, renderer, ctx)
            times[renderer].append((time.perf_counter() - start) * 1e3)
    sizes = fastest.scene_sizes(scene)
    choice = fastest.choose("auto", *sizes, ctx.info["GL_RENDERER"], fastest.ray_queries(),
                            first=False)   # warmed up: the one-off costs are paid
    ms = {r: statistics.median(v) for r, v in times.items()}
    return {"scene": scene.name or "scene", "triangles": sizes[0], "pixels": sizes[1],
            "lights": sizes[2], "ms": ms, "model": [choice.raster_ms, choice.raytrace_ms],
            "chosen": choice.renderer, "faster": min(ms, key=ms.get),
            "chosen_over_best": ms[choice.renderer] / min(ms.values())}


# a fresh process's first masks and its second, of a tiny scene: the one-off costs
FIRST_CHILD = """
import time
from shadowvol.compare import fastest
from shadowvol.scenefile import load_scene
scene = load_scene({scene!r}).replace(width=32, height=24)
ctx = None
if {renderer!r} == "shadowvol":
    from shadowvol.raster.platform.context import create_context
    ctx = create_context()
times = []
for _ in range(2):
    start = time.perf_counter()
    fastest.masks(scene, {renderer!r}, ctx)
    times.append((time.perf_counter() - start) * 1e3)
print(times[0], times[1])
"""


def first_costs(runs: int) -> dict:
    """ms of the one-off costs of a fresh process's first masks (its first minus its second
    masks of a 32x24 scene), per renderer and, for the ray tracer, per Embree queries
    ($SHADOWVOL_EMBREE); medians of `runs` processes each."""
    out = {}
    scene = str(ROOT / "scenes" / "stack.toml")
    for name, renderer, queries in (("shadowvol", "shadowvol", "auto"),
                                    ("raytrace, packets", "raytrace", "packets"),
                                    ("raytrace, single rays", "raytrace", "single")):
        gaps = []
        for _ in range(runs):
            done = subprocess.run([sys.executable, "-c", FIRST_CHILD.format(
                scene=scene, renderer=renderer)], cwd=ROOT, capture_output=True, text=True,
                env={**os.environ, "SHADOWVOL_EMBREE": queries}, timeout=300)
            if done.returncode != 0:
                break
            first, second = (float(x) for x in done.stdout.split()[-2:])
            gaps.append(first - second)
        out[name] = statistics.median(gaps) if gaps else None
    return out


def fit(rows: list[dict]) -> dict:
    """The model's constants (`fastest`'s names) fitted to the rows' wall ms."""
    from scipy.optimize import nnls

    from shadowvol.compare import fastest

    T, P, L = (np.array([r[k] for r in rows], np.float64) for k in ("triangles", "pixels",
                                                                       "lights"))
    raster = np.array([r["ms"]["shadowvol"] for r in rows]) * 1e6
    rays = np.array([r["ms"]["raytrace"] for r in rows]) * 1e6
    a, _ = nnls(np.stack([np.full_like(T, 1e6), T, T * L, P * L], axis=1), raster)
    b, _ = nnls(np.stack([T, P * (1 + fastest.SHADOW_RAY_SHARE * L)], axis=1), rays)
    return {"RASTER_MS": a[0], "RASTER_NS_PER_TRIANGLE": a[1],
            "RASTER_NS_PER_TRIANGLE_LIGHT": a[2], "RASTER_NS_PER_PIXEL_LIGHT": a[3],
            "RAYS_NS_PER_TRIANGLE": b[0], "RAYS_NS_PER_RAY": b[1]}


def table(result: dict) -> list[str]:
    lines = ["| scene | triangles | size (pixels) | hard lights | raster ms | ray tracer ms | "
             "model: raster / rays ms | auto chose | chosen / faster |",
             "|---|---:|---:|---:|---:|---:|---:|---|---:|"]
    for r in result["scenes"]:
        lines.append(f"| {r['scene']} | {r['triangles']:,} | {r['pixels']:,} | {r['lights']} | "
                     f"{r['ms']['shadowvol']:.0f} | {r['ms']['raytrace']:.0f} | "
                     f"{r['model'][0]:.0f} / {r['model'][1]:.0f} | {r['chosen']} | "
                     f"{r['chosen_over_best']:.2f} |")
    right = sum(r["chosen"] == r["faster"] for r in result["scenes"])
    worst = max(r["chosen_over_best"] for r in result["scenes"])
    lines += ["", f"auto chose the faster renderer on {right} of {len(result['scenes'])} "
                  f"scenes; its worst choice cost {worst:.2f}x the faster one",
              "fitted to this run: " + ", ".join(f"{k} {v:.1f}" for k, v in
                                                  result["fit"].items()),
              "a fresh process's first masks, ms more than its second (RASTER_FIRST_MS, "
              "RAYS_FIRST_MS): " + ", ".join(
                  f"{k} {'-' if v is None else f'{v:.0f}'}" for k, v in result["first"].items())]
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.bench_fastest",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="two tiny scenes (a smoke run)")
    ap.add_argument("--json", type=str, default=None)
    args = ap.parse_args(argv)
    from shadowvol.raster.platform.context import create_context

    load = os.getloadavg()
    ctx = create_context()
    try:
        rows = [measure(scene, ctx, args.runs) for scene in bench_scenes(args.quick)]
        result = {"runs": args.runs, "gl_renderer": ctx.info["GL_RENDERER"], "scenes": rows,
                  "fit": fit(rows), "first": first_costs(args.runs),
                  "load": [load, os.getloadavg()]}
    finally:
        ctx.release()
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=1))
    print(f"{result['gl_renderer']}, {args.runs} rounds interleaved; load "
          f"{load[0]:.1f} -> {os.getloadavg()[0]:.1f}")
    print("\n".join(table(result)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
