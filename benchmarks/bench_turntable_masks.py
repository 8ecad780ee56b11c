"""Benchmark (not a test): `raytrace.shadow_masks` per view of the turntable, across checkouts.

    python -m benchmarks.bench_turntable_masks [--views 36] [--rounds 3]
           [--against PATH ...] [--queries auto|packets|single ...] [--json FILE]

The scene: the five shared meshes (../shared/models beside the checkout: bunny, teapot,
suzanne, spot, lampshade, `scenes.turntable_scene`) on a floor at 640x480, under a point, a
directional and a spot light, seen from `--views` cameras around it; without the shared
meshes (the project does not ship them) the 100k-triangle procedural scene under the same
lights stands in, and the output says so.  Each view is a fresh `shadow_masks(view)`, as
`raytrace masks` and the benchmark's turntable section call it: the backend is built per view.

Every checkout (this one first, then each `--against` folder, e.g. a `git worktree add` of an
older commit) is measured in processes of its own that import `raytrace` from it, taking
turns round by round; each process reports the CPU time (all threads) and the wall time per
view, and the table gives the medians over all views of all rounds, and each checkout's CPU
median over this one's.  The scene is built by this file's `benchmarks.scenes` in every
process, so all see the same triangles.  `--queries` measures each checkout once per choice
of Embree queries ($SHADOWVOL_EMBREE in its processes: `raytrace.embree.embree_queries`),
e.g. `--queries single packets` for embreex's single rays against Embree's packets.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = """
import importlib.util, json, sys, time
sys.path.insert(0, {code!r})
spec = importlib.util.spec_from_file_location("bench_scenes", {scenes!r})
scenes = importlib.util.module_from_spec(spec)
spec.loader.exec_module(scenes)
from shadowvol import DirectionalLight, PointLight, SpotLight
import raytrace
from raytrace import shadow_masks
lights = (PointLight([-3.0, 5.0, 2.0]), DirectionalLight([0.4, -1.0, -0.3]),
          SpotLight([3.0, 4.0, 3.0], [-3.0, -4.0, -3.0], cone_angle=35.0))
shared = scenes.models_dir() is not None
if shared:
    scene = scenes.turntable_scene(640, 480)
else:
    scene = scenes.occluder_scene("100k", 1, 640, 480)
scene = scene.replace(lights=lights)
shadow_masks(scene)  # warm-up: imports, the thread pool, Embree
cpu, wall, lit = [], [], 0
for cam in scenes.turntable_cameras({views}):
    view = scene.replace(camera=cam)
    c0, w0 = time.process_time(), time.perf_counter()
    masks, _ = shadow_masks(view)
    cpu.append(time.process_time() - c0)
    wall.append(time.perf_counter() - w0)
    lit += int(masks.sum())
print(json.dumps(dict(cpu=cpu, wall=wall, lit=lit, shared=shared,
                      raytrace=raytrace.__file__,
                      triangles=sum(len(o.faces) for o in scene.objects))))
"""


def measure(code: Path, views: int, queries: str | None = None) -> dict:
    """One process importing raytrace from the checkout `code` (Embree's `queries`, None:
    as the environment says): its per-view times."""
    child = CHILD.format(code=str(code), scenes=str(ROOT / "benchmarks" / "scenes.py"),
                         views=views)
    env = dict(os.environ, PYTHONPATH=str(code))
    if queries:
        env["SHADOWVOL_EMBREE"] = queries
    done = subprocess.run([sys.executable, "-c", child], cwd=code, env=env,
                          capture_output=True, text=True, check=True)
    return json.loads(done.stdout.splitlines()[-1])


def run(checkouts: list[Path], views: int, rounds: int, queries=(None,)) -> dict:
    """Every checkout measured `rounds` times per choice of `queries`, taking turns; medians in
    ms per view."""
    variants = [(c, q) for c in checkouts for q in queries]
    samples = {v: {"cpu": [], "wall": [], "lit": set(), "runs": []} for v in variants}
    for _ in range(rounds):
        for c, q in variants:
            r = measure(c, views, q)
            s = samples[(c, q)]
            s["cpu"] += r["cpu"]
            s["wall"] += r["wall"]
            s["lit"].add(r["lit"])
            s["runs"].append(statistics.median(r["cpu"]) * 1e3)
            shared, triangles = r["shared"], r["triangles"]
    first = statistics.median(samples[variants[0]]["cpu"])
    rows = []
    for c, q in variants:
        s = samples[(c, q)]
        cpu = statistics.median(s["cpu"])
        rows.append({"checkout": str(c) + (f" ({q})" if q else ""), "commit": _commit(c),
                     "cpu_ms": cpu * 1e3, "wall_ms": statistics.median(s["wall"]) * 1e3,
                     "cpu_ms_per_run": s["runs"], "over_first": cpu / first,
                     "lit_pixels": sorted(s["lit"])})
    return {"views": views, "rounds": rounds, "shared_meshes": shared, "triangles": triangles,
            "load": os.getloadavg(), "rows": rows}


def _commit(path: Path) -> str:
    done = subprocess.run(["git", "-C", str(path), "describe", "--always", "--dirty"],
                          capture_output=True, text=True)
    return done.stdout.strip() or "?"


def table(result: dict) -> str:
    scene = ("the shared meshes" if result["shared_meshes"] else
             "the 100k procedural scene (../shared/models not found)")
    lines = [f"{scene}, {result['triangles']} triangles, {result['views']} views x "
             f"{result['rounds']} rounds, load {result['load'][0]:.1f}", "",
             "| checkout | commit | CPU ms/view | wall ms/view | CPU / first |",
             "|---|---|---:|---:|---:|"]
    for r in result["rows"]:
        lines.append(f"| {r['checkout']} | {r['commit']} | {r['cpu_ms']:.0f} | "
                     f"{r['wall_ms']:.0f} | {r['over_first']:.2f}x |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.bench_turntable_masks",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--views", type=int, default=36)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--against", type=Path, nargs="*", default=[],
                    help="other checkouts to measure in the same run (their raytrace)")
    ap.add_argument("--queries", nargs="*", default=[None],
                    choices=["auto", "packets", "single"],
                    help="Embree's queries ($SHADOWVOL_EMBREE), each measured in turn")
    ap.add_argument("--json", type=Path, help="write every number here")
    args = ap.parse_args(argv)
    result = run([ROOT] + [p.resolve() for p in args.against], args.views, args.rounds,
                 args.queries or [None])
    if args.json:
        args.json.write_text(json.dumps(result, indent=1))
    print(table(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
