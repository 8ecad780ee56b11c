"""Benchmark (not a test): our exact masks against the peers' on the benchmark scenes, in one run.

    python -m benchmarks.bench_peers [--runs 5] [--quick] [--json FILE]

Scenes (1280x720 unless said): the procedural 100k and 1M scenes under one point light
(`scenes.occluder_scene`), two Stanford bunnies on a floor (139k triangles) under a point and a
directional light, and four views of the turntable (640x480, the five shared meshes, a point,
a directional and a spot light; times per view).  Without ../shared/models the last two are
left out and the output says so.  `--quick`: the 1k scene at 160x90 and, with the shared
meshes, two turntable views at 160x120, one round (a smoke run for the tests).

Variants, taking turns round by round (every other round in reverse order), wall and CPU time
(every thread) of each, medians:

* ray tracer: `raytrace.shadow_masks` on Embree backends built before the clock (one a view:
  its frame's origin is the eye);
* raster masks: the rasterizer's mask-only frame, `Renderer.render(outputs=("lit",
  "coverage"))`, one renderer whose camera changes;
* Open3D: `bench_open3d.Open3DMasks`, the naive script of `RaycastingScene` (`open3d-cpu`, the
  bench extra), its scene built before the clock;
* Mitsuba 3 `llvm_ad_rgb` (the bench extra): `bench_mitsuba.MitsubaMasks.all_lights`, where
  its JIT runs: a child process tries it first, since on some CPUs (AVX-512 with Debian's
  LLVM 15: "Cannot select: fmaximum") it fails, and the output says why;
* the ground truth (`--outputs all`: every `shadowvol.frame.GROUND_TRUTH` output) of each
  renderer, against its masks alone.

Then, per scene: ours (the faster of the ray tracer and the raster masks) over the fastest peer;
the pixels where each differs from the ray tracer's masks (the peers offset their shadow rays,
so they are not exact; the raster masks are counted the same way, not judged); the rays (one primary per pixel,
one shadow ray per facing pixel and light, from the ground truth's facing) and the ray
tracer's cost per ray per core (wall time x threads / rays, and CPU time / rays); and the ray
tracer on 1 and on 2 threads (interleaved) and their ratio.
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from . import scenes
from .cli import bench_main
from .bench_masks import BUNNY

ROOT = Path(__file__).resolve().parents[1]
MASKS = ("lit", "coverage")
# a child process tries Mitsuba's JIT on a tiny scene before this one imports it (it may abort)
MITSUBA_PROBE = """
import sys
sys.path.insert(0, {root!r})
from benchmarks import scenes
from benchmarks.bench_mitsuba import MitsubaMasks
MitsubaMasks(scenes.occluder_scene("1k", 1, 32, 24)).all_lights()
print("ok")
"""


def two_bunnies(width: int, height: int):
    """Two Stanford bunnies (69k triangles each) on a 6 x 6 floor, a point and a directional
    light."""
    import trimesh

    from shadowvol import Camera, DirectionalLight, Material, PointLight, Scene
    from shadowvol.primitives import Transform, mesh, plane

    loaded = trimesh.load(str(BUNNY), process=False)
    v, f = np.asarray(loaded.vertices), np.asarray(loaded.faces)
    scale = 1.5 / float(np.ptp(v[:, 1]))
    base, centre = v.min(axis=0) * scale, (v.max(axis=0) + v.min(axis=0)) / 2 * scale
    bunnies = [mesh(f"bunny{i}", v, f, Material(diffuse=[0.8, 0.7, 0.6]),
                    Transform(scale=scale, rotation=(0.0, angle, 0.0),
                              translation=[x - centre[0], -base[1], -centre[2]]))
               for i, (x, angle) in enumerate(((-0.9, 0.0), (0.9, 60.0)))]
    return Scene(camera=Camera(eye=[0.0, 1.8, 4.6], target=[0.0, 0.65, 0.0], fov_y=40.0),
                 objects=(plane("floor", size=[6.0, 6.0]), *bunnies),
                 lights=(PointLight([-2.0, 4.0, 2.5]), DirectionalLight([0.4, -1.0, -0.3])),
                 width=width, height=height, name="two bunnies")


def bench_scenes(quick: bool) -> tuple[list[tuple[str, list]], str | None]:
    """[(name, [views])]: each a list of scenes differing only in the camera; and a note of
    what was left out, or None."""
    from shadowvol import DirectionalLight, PointLight, SpotLight

    shared = scenes.models_dir() is not None and BUNNY.is_file()
    note = None if shared else "the shared meshes are missing: bunnies and turntable left out"
    if quick:
        out = [("1k", [scenes.occluder_scene("1k", 1, 160, 90)])]
        views, size = 2, (160, 120)
    else:
        out = [(s, [scenes.occluder_scene(s, 1, 1280, 720)]) for s in ("100k", "1M")]
        if shared:
            out.append(("two bunnies", [two_bunnies(1280, 720)]))
        views, size = 4, (640, 480)
    if shared:
        lights = (PointLight([-3.0, 5.0, 2.0]), DirectionalLight([0.4, -1.0, -0.3]),
                  SpotLight([3.0, 4.0, 3.0], [-3.0, -4.0, -3.0], cone_angle=35.0))
        scene = scenes.turntable_scene(*size).replace(lights=lights)
        cameras = scenes.turntable_cameras(36)[::36 // views][:views]
        out.append((f"turntable ({views} views)", [scene.replace(camera=c) for c in cameras]))
    return out, note


def mitsuba_reason() -> str | None:
    """None where Mitsuba 3's llvm_ad_rgb runs here, else why not (one line)."""
    try:
        import mitsuba  # noqa: F401
    except ImportError:
        return "Mitsuba 3 is not installed (pip install '.[bench]')"
    try:
        done = subprocess.run([sys.executable, "-c", MITSUBA_PROBE.format(root=str(ROOT))],
                              capture_output=True, text=True, timeout=300, cwd=ROOT)
    except subprocess.TimeoutExpired:
        return "Mitsuba 3's llvm_ad_rgb did not finish a 32x24 frame in 300 s"
    if done.returncode == 0 and done.stdout.strip().endswith("ok"):
        return None
    lines = [ln.strip() for ln in done.stderr.splitlines() if ln.strip()]
    why = next((ln for ln in lines if "Cannot select" in ln), lines[-1] if lines else
               f"exit status {done.returncode}")
    return f"Mitsuba 3's llvm_ad_rgb JIT does not run on this CPU: {why[:200]}"


def open3d_reason() -> str | None:
    try:
        import open3d  # noqa: F401
    except ImportError as exc:
        return f"Open3D is not installed or does not load ({exc}); pip install open3d-cpu"
    return None


def interleaved(fns: dict, runs: int) -> dict:
    """{name: {"wall", "cpu"}} medians in ms of each function (one call a round), after one
    untimed round; every other round in reverse order."""
    for fn in fns.values():
        fn()
    times = {k: {"wall": [], "cpu": []} for k in fns}
    for r in range(runs):
        order = list(fns.items())
        for k, fn in (order if r % 2 == 0 else order[::-1]):
            w, c = time.perf_counter(), time.process_time()
            fn()
            times[k]["wall"].append((time.perf_counter() - w) * 1e3)
            times[k]["cpu"].append((time.process_time() - c) * 1e3)
    return {k: {m: statistics.median(v[m]) for m in ("wall", "cpu")} for k, v in times.items()}


def _each(fn, views: list):
    """A function calling fn(i, view) for every view."""
    return lambda: [fn(i, v) for i, v in enumerate(views)]


def variants(views: list, ctx, renderer, peers: dict) -> tuple[dict, dict]:
    """The timed functions of a scene's views, and the backends and peers built for them."""
    from raytrace import ground_truth, shadow_masks
    from raytrace.masks import scene_backend
    from shadowvol.raster.platform.context import make_current

    backends = [scene_backend(v) for v in views]
    built = {"backends": backends}

    def raster(outputs):
        def frame(i, view):
            make_current(ctx)
            return renderer.render(camera=view.camera, outputs=outputs)
        return frame

    fns = {"ray tracer": _each(lambda i, v: shadow_masks(v, backends[i]), views),
           "raster masks": _each(raster(MASKS), views),
           "ray tracer, all outputs": _each(lambda i, v: ground_truth(v, backend=backends[i]),
                                            views),
           "raster, all outputs": _each(raster(MASKS + _truth()), views)}
    if peers.get("Open3D") is None:
        from .bench_open3d import Open3DMasks
        built["Open3D"] = [Open3DMasks(v) for v in views]
        fns["Open3D"] = _each(lambda i, v: built["Open3D"][i](), views)
    if peers.get("Mitsuba 3") is None:
        from .bench_mitsuba import MitsubaMasks
        built["Mitsuba 3"] = [MitsubaMasks(v) for v in views]
        fns["Mitsuba 3"] = _each(lambda i, v: built["Mitsuba 3"][i].all_lights(), views)
    return fns, built


def _truth() -> tuple[str, ...]:
    from shadowvol.frame import GROUND_TRUTH
    return GROUND_TRUTH


def agreement(views: list, ctx, renderer, built: dict) -> dict:
    """Pixels (lit of every light, and coverage) where each variant differs from the ray
    tracer's masks, summed over the views; and the rays the ray tracer casts."""
    from raytrace import ground_truth
    from shadowvol.raster.platform.context import make_current

    differ = {k: 0 for k in ("raster masks", "Open3D", "Mitsuba 3") if k in built or
              k == "raster masks"}
    primary = shadow = 0
    for i, view in enumerate(views):
        truth = ground_truth(view, ("facing",), backend=built["backends"][i])
        primary += view.width * view.height
        shadow += int(truth.facing.sum())
        make_current(ctx)
        masks = renderer.render(camera=view.camera, outputs=MASKS)
        theirs = {"raster masks": (masks.lit, masks.coverage)}
        if "Open3D" in built:
            theirs["Open3D"] = built["Open3D"][i]()
        if "Mitsuba 3" in built:
            theirs["Mitsuba 3"] = built["Mitsuba 3"][i].all_lights()
        for k, (lit, cov) in theirs.items():
            differ[k] += int((lit != truth.lit).sum() + (cov != truth.coverage).sum())
    return {"differing": differ, "primary_rays": primary, "shadow_rays": shadow}


def thread_scaling(views: list, built: dict, runs: int) -> dict:
    """The ray tracer's masks on 1 and on 2 threads (its backends' `threads`), interleaved:
    {"1": ms, "2": ms} medians of wall and CPU time, and wall(1) / wall(2)."""
    from raytrace import shadow_masks

    tracers = [b.tracer for b in built["backends"]]
    before = [t.threads for t in tracers]

    def on(n):
        def run():
            for t in tracers:
                t.threads = n
            for view, backend in zip(views, built["backends"]):
                shadow_masks(view, backend)
        return run
    try:
        times = interleaved({"1": on(1), "2": on(2)}, runs)
    finally:
        for t, n in zip(tracers, before):
            t.threads = n
    return {"ms": times, "speedup": times["1"]["wall"] / times["2"]["wall"]}


def measure(quick: bool, runs: int) -> dict:
    from shadowvol import Renderer
    from shadowvol.raster.platform.context import create_context

    peers = {"Open3D": open3d_reason(), "Mitsuba 3": mitsuba_reason()}
    todo, note = bench_scenes(quick)
    ctx = create_context()
    rows = []
    try:
        for name, views in todo:
            with Renderer(views[0], ctx) as renderer:
                fns, built = variants(views, ctx, renderer, peers)
                ms = {k: {m: t / len(views) for m, t in v.items()}
                      for k, v in interleaved(fns, runs).items()}
                rows.append({"scene": name, "views": len(views),
                             "triangles": scenes.triangle_count(views[0]),
                             "size": [views[0].width, views[0].height],
                             "lights": len(views[0].lights), "ms": ms,
                             **agreement(views, ctx, renderer, built),
                             "threads": thread_scaling(views, built, runs)})
                rows[-1]["threads"]["ms"] = {k: {m: t / len(views) for m, t in v.items()}
                                             for k, v in rows[-1]["threads"]["ms"].items()}
                rows[-1]["cores"] = built["backends"][0].tracer.threads
    finally:
        ctx.release()
    return {"runs": runs, "quick": quick, "note": note, "peers_skipped": peers,
            "load": os.getloadavg(), "scenes": rows}


def summary(row: dict) -> dict:
    """Ours (the faster of the two) over the fastest peer, the ground truth over the masks,
    and the ray tracer's ns per ray per core."""
    ms = {k: v["wall"] for k, v in row["ms"].items()}
    ours = min(ms["ray tracer"], ms["raster masks"])
    peer = min((ms[k] for k in ("Open3D", "Mitsuba 3") if k in ms), default=None)
    rays = (row["primary_rays"] + row["shadow_rays"]) / row["views"]
    return {"ours_ms": ours, "ours_by": "ray tracer" if ms["ray tracer"] <= ms["raster masks"]
            else "raster masks", "peer_ms": peer,
            "ours_over_peer": None if peer is None else ours / peer,
            "truth_over_masks": {"ray tracer": ms["ray tracer, all outputs"] / ms["ray tracer"],
                                 "raster": ms["raster, all outputs"] / ms["raster masks"]},
            "ns_per_ray_core": ms["ray tracer"] * 1e6 * row["cores"] / rays,
            "cpu_ns_per_ray": row["ms"]["ray tracer"]["cpu"] * 1e6 / rays}


def table(result: dict) -> list[str]:
    keys = ["ray tracer", "raster masks", "Open3D", "Mitsuba 3", "ray tracer, all outputs",
            "raster, all outputs"]
    lines = [f"{result['runs']} rounds interleaved; load {result['load'][0]:.1f}; ms median "
             "wall / CPU (all threads), per view", ""]
    lines += [f"{k} skipped: {why}" for k, why in result["peers_skipped"].items() if why]
    lines += [result["note"]] if result["note"] else []
    lines += ["", "| scene | triangles | size | lights | " + " | ".join(keys) +
              " | ours / best peer | all outputs / masks (rt, raster) | pixels differing "
              "(raster, Open3D, Mitsuba) |", "|---|---:|---|---:|" + "---:|" * (len(keys) + 3)]
    for r in result["scenes"]:
        s = summary(r)
        cells = " | ".join(f"{r['ms'][k]['wall']:.0f} / {r['ms'][k]['cpu']:.0f}"
                           if k in r["ms"] else "-" for k in keys)
        ratio = "-" if s["ours_over_peer"] is None else \
            f"{s['ours_over_peer']:.2f} ({s['ours_by']})"
        truth = s["truth_over_masks"]
        differ = ", ".join(str(r["differing"].get(k, "-"))
                           for k in ("raster masks", "Open3D", "Mitsuba 3"))
        lines.append(f"| {r['scene']} | {r['triangles']:,} | {r['size'][0]}x{r['size'][1]} | "
                     f"{r['lights']} | {cells} | {ratio} | {truth['ray tracer']:.2f}, "
                     f"{truth['raster']:.2f} | {differ} |")
    lines += ["", "| scene | primary + shadow rays a view | ray tracer ns / ray / core "
              "(wall x cores) | CPU ns / ray | 1 thread (ms) | 2 threads (ms) | 1 -> 2 |",
              "|---|---:|---:|---:|---:|---:|---:|"]
    for r in result["scenes"]:
        s, t = summary(r), r["threads"]
        rays = (r["primary_rays"] + r["shadow_rays"]) // r["views"]
        lines.append(f"| {r['scene']} | {rays:,} | {s['ns_per_ray_core']:.0f} | "
                     f"{s['cpu_ns_per_ray']:.0f} | {t['ms']['1']['wall']:.0f} | "
                     f"{t['ms']['2']['wall']:.0f} | {t['speedup']:.2f}x |")
    return lines


def main(argv=None) -> int:
    def run(args) -> dict:
        result = measure(args.quick, 1 if args.quick else args.runs)
        for r in result["scenes"]:
            r["summary"] = summary(r)
        return result

    return bench_main(argv, "bench_peers", __doc__, run,
                      lambda result, _: "\n".join(table(result)), quick=True)


if __name__ == "__main__":
    sys.exit(main())
