"""Benchmark (not a test): exact instance-shadow pairs at scale, `shadowvol batch --format
soba-lights` on the shared meshes.

    python -m benchmarks.bench_soba [--models DIR] [--pairs 36000] [--width 160 --height 120]
                                    [--views 12] [--seed 0] [--json out.json]

SOBA (Wang et al., CVPR 2020) has 3,623 object-shadow pairs drawn by hand.  This makes at
least `--pairs` exact ones: scenes of the five shared meshes (../shared/models beside the
checkout, or $SHADOWVOL_MODELS, or --models), each mesh placed twice at a random position and
turn on a floor (the background: `cast_shadows` false), a point and a directional light at
random, an orbit of `--views` cameras per scene with the batch's eye and light jitter; scenes
are added until the pairs the first scenes gave, extrapolated, reach `--pairs`.  A pair is one
object and its shadow under one light (`soba-lights`: the object's `casters` bit of that
light), as `association_anno` counts them.  One worker (this process), 2 cores shared with
whatever else runs: wall time, pairs/s, frames/s and the peak RSS of this process
(ru_maxrss; the run renders in it).

When the models folder is absent it prints why and returns {"skipped": reason}.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MODELS = Path(os.environ.get("SHADOWVOL_MODELS", ROOT.parent / "shared" / "models"))
NAMES = ("bunny", "teapot", "suzanne", "spot", "lampshade")
COPIES = 2            # each mesh this many times per scene
PROBE_SCENES = 3      # scenes made first, to learn the pairs per frame


def _meshes(models: Path) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    import trimesh

    found = {}
    for name in NAMES:
        m = trimesh.load(str(models / f"{name}.obj"), process=False)
        found[name] = (np.asarray(m.vertices, np.float64), np.asarray(m.faces))
    return found


def make_scene(meshes: dict, rng: np.random.Generator, width: int, height: int, index: int):
    """The five meshes, COPIES times each, at random spots and turns on a 7 x 7 floor (the
    background), a point and a directional light at random."""
    from shadowvol.primitives import Transform, mesh, plane
    from shadowvol.scene import Camera, DirectionalLight, PointLight, Scene

    objects = [replace(plane("floor", size=[9.0, 9.0]), cast_shadows=False)]
    for copy in range(COPIES):
        for name, (v, f) in meshes.items():
            scale = float(rng.uniform(0.7, 1.1)) / float(np.ptp(v, axis=0).max())
            x, z = rng.uniform(-3.0, 3.0, 2)
            yaw = float(rng.uniform(0.0, 360.0))
            # stand it on the floor: its lowest point (after the turn about y) at y = 0
            moved = Transform(scale=scale, rotation=(0.0, yaw, 0.0)).points(v)
            t = [x - float(moved[:, 0].mean()), -float(moved[:, 1].min()),
                 z - float(moved[:, 2].mean())]
            objects.append(mesh(f"{name} {copy}", v, f, transform=Transform(
                scale=scale, rotation=(0.0, yaw, 0.0), translation=t)))
    point = rng.uniform([-2.5, 3.0, -2.5], [2.5, 4.5, 2.5])
    direction = np.array([rng.uniform(-0.6, 0.6), -1.0, rng.uniform(-0.6, 0.6)])
    lights = (PointLight(position=point, intensity=0.7),
              DirectionalLight(direction=direction, intensity=0.5))
    camera = Camera(eye=[0.0, 5.0, 7.0], target=[0.0, 0.3, 0.0], fov_y=50.0)
    return Scene(camera=camera, objects=tuple(objects), lights=lights, width=width,
                 height=height, ambient=[0.12, 0.12, 0.12], name=f"soba-{index}")


def _job(scene, index: int, views: int, seed: int) -> dict:
    return {"name": f"scene-{index:04d}", "scene": scene, "seed": seed + index,
            "jitter": {"eye": 0.3, "lights": 0.3},
            "cameras": {"orbit": {"center": [0.0, 0.3, 0.0], "radius": 7.5, "elevation": 35.0,
                                  "start": float(index * 7 % 360), "frames": views}}}


def _pairs(out: Path) -> int:
    return sum(len(json.loads(p.read_text())["association_anno"])
               for p in out.glob("*/annotations.json"))


def measure(models: Path = MODELS, pairs: int = 36000, width: int = 160, height: int = 120,
            views: int = 12, seed: int = 0) -> dict:
    if not all((models / f"{name}.obj").is_file() for name in NAMES):
        return {"skipped": f"the shared meshes are not in {models} (set $SHADOWVOL_MODELS or "
                           "--models)"}
    import shadowvol.batch as batch

    rng = np.random.default_rng(seed)
    meshes = _meshes(models)
    folder = Path(tempfile.mkdtemp(prefix="bench-soba-"))
    try:
        start = time.perf_counter()
        jobs = [_job(make_scene(meshes, rng, width, height, i), i, views, seed)
                for i in range(PROBE_SCENES)]
        summary = batch.run(jobs, folder / "out", format="soba-lights", progress=False)
        assert summary.status == 0, summary.errors
        made = _pairs(folder / "out")
        per_scene = made / PROBE_SCENES
        scenes = PROBE_SCENES + max(0, int(np.ceil((pairs - made) / max(per_scene, 1e-9))))
        while True:
            jobs += [_job(make_scene(meshes, rng, width, height, i), i, views, seed)
                     for i in range(len(jobs), scenes)]
            summary = batch.run(jobs, folder / "out", format="soba-lights", progress=False)
            assert summary.status == 0, summary.errors
            made = _pairs(folder / "out")
            if made >= pairs:
                break
            scenes += max(1, int(np.ceil((pairs - made) / per_scene)))
        seconds = time.perf_counter() - start
        frames = len(jobs) * views
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        return {"pairs": made, "frames": frames, "scenes": len(jobs), "seconds": seconds,
                "pairs_per_s": made / seconds, "frames_per_s": frames / seconds,
                "pairs_per_frame": made / frames, "peak_rss_mb": peak,
                "size": [width, height], "objects_per_scene": 1 + COPIES * len(NAMES),
                "triangles_per_scene": 2 + COPIES * sum(len(f) for _, f in meshes.values()),
                "cores": len(os.sched_getaffinity(0)), "format": "soba-lights"}
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def report(r: dict) -> str:
    if "skipped" in r:
        return f"skipped: {r['skipped']}"
    return "\n".join([
        f"--format soba-lights, one worker, {r['cores']} cores, {r['size'][0]}x{r['size'][1]}, "
        f"{r['objects_per_scene']} objects ({r['triangles_per_scene']:,} triangles) and 2 lights "
        f"per scene",
        "| pairs | frames | scenes | seconds | pairs/s | frames/s | pairs/frame | peak RSS MB |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|",
        f"| {r['pairs']:,} | {r['frames']:,} | {r['scenes']} | {r['seconds']:.0f} | "
        f"{r['pairs_per_s']:.1f} | {r['frames_per_s']:.2f} | {r['pairs_per_frame']:.2f} | "
        f"{r['peak_rss_mb']:.0f} |"])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--models", type=Path, default=MODELS)
    ap.add_argument("--pairs", type=int, default=36000)
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--height", type=int, default=120)
    ap.add_argument("--views", type=int, default=12)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args(argv)
    r = measure(args.models, args.pairs, args.width, args.height, args.views, args.seed)
    print(report(r))
    if args.json is not None:
        args.json.write_text(json.dumps(r, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
