"""Every benchmark of shadowvol in one reproducible run; writes BENCHMARKS.md and its plot.

    python -m benchmarks.run            # the full run (~12-15 min on 2 cores / llvmpipe)
    python -m benchmarks.run --quick    # a smoke run on small scenes (seconds), into --out

What it measures (medians of several runs after warm-up, with min and max), every ratio from
variants interleaved round by round in the same run:

* frames at 1280x720 of the procedural scenes of `scenes` (~1k, 100k and 1M triangles): the
  PLAIN moderngl frame of the same triangles (`plain`: one indexed draw, back-face culling,
  Blinn-Phong, RGBA8 read-back), the floor (our frame without shadow volumes), the shadowed
  frame (auto, CPU silhouettes) with 1, 2 and 4 point lights, GPU silhouettes, mask-only frames
  (`outputs=("lit", "coverage")`), and the opt-in back-face culling; and the least GL work of
  any exact frame (`plain.DepthFloor`; `plain.ImageFloor` and `plain.LightingFloor` for one
  that returns the image);
* each phase of a frame (`frames`: glFinish-bracketed wall time), and silhouette extraction
  alone on the CPU and the GPU;
* the stencil-overflow check's cost on the shared meshes (bunny, teapot, Spot);
* a 36-view turntable (640x480, the five shared meshes and a floor, 3 lights): our masks and
  image per view against `raytrace.shadow_masks` of the same views;
* pyrender 0.1.45's shadow-mapped frame of the same scenes (spot and directional light);
* peak RSS of a 1M-triangle frame against the ray tracer's masks of it (separate processes);
* raytrace masks against raw embreex casts of the same rays (`bench_masks.measure`), and a full
  Whitted render.

The markdown is written by this script from the measured numbers, plus the hand-written
history of the optimisations (`benchmarks/OPTIMISATIONS.md`) included verbatim.  Mitsuba 3 is
an optional peer that this run does not install or time.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from importlib import metadata
from pathlib import Path

from . import bench_groundtruth, bench_masks, frames, plain, report, scenes

ROOT = Path(__file__).resolve().parents[1]

FULL = dict(
    sizes=("1k", "100k", "1M"), lights=(1, 2, 4), size=(1280, 720),
    # (warm-up, timed) rounds per size: fewer at 1M, where one round takes seconds
    repeat={"1k": (2, 9), "100k": (2, 9), "1M": (1, 4)},
    phase_repeat={"1k": 5, "100k": 5, "1M": 2},
    # the check's cost is a few % of a 30-90 ms frame: more rounds than the frames, in
    # alternating order
    overflow_meshes=("bunny", "teapot", "spot"), overflow_repeat=(2, 25),
    turntable=dict(views=36, size=(640, 480)),
    pyrender_sizes=("1k", "100k", "1M"),
    pyrender_repeat={"1k": (2, 5), "100k": (2, 5), "1M": (1, 2)},
    rss_size="1M",
    mask_sizes=("100k", "1M"), mask_runs=5, bunny=True,
    whitted_size=(1280, 720), whitted_runs=3,
    truth_size="100k", truth_runs=7,
    # the Python of a frame against the number of objects (64 x 48: small draws)
    object_counts=(20, 1000, 5000), object_repeat=15,
)
QUICK = dict(
    sizes=("1k",), lights=(1, 2), size=(320, 180),
    repeat={"1k": (1, 2)}, phase_repeat={"1k": 1},
    overflow_meshes=("spot",), overflow_repeat=(1, 2),
    turntable=dict(views=2, size=(160, 120)),
    pyrender_sizes=("1k",), pyrender_repeat={"1k": (1, 2)},
    rss_size="1k",
    mask_sizes=("1k",), mask_runs=1, bunny=False,
    whitted_size=(160, 90), whitted_runs=1,
    truth_size="1k", truth_runs=1,
    object_counts=(20, 200), object_repeat=2,
)
SILHOUETTES = frames.SILHOUETTES
MASKS = ("lit", "coverage")


def log(*args) -> None:
    print(time.strftime("%H:%M:%S"), *args, file=sys.stderr, flush=True)


def maxrss_mb() -> float:
    """Peak resident set size of this process so far (Linux reports KiB), in MB."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


# ---------------------------------------------------------------------------------------------
# The machine
# ---------------------------------------------------------------------------------------------

def machine(ctx) -> dict:
    cpu = platform.processor() or "?"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    versions = {}
    for pkg in ("numpy", "moderngl", "glcontext", "embreex", "pyrender", "PyOpenGL", "trimesh",
                "matplotlib", "mitsuba", "numba"):
        try:
            versions[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            versions[pkg] = "not installed"
    try:
        commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                                capture_output=True, text=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--",
                                "shadowvol", "raytrace", "shaders", "benchmarks"],
                               capture_output=True, text=True).stdout
    except OSError:
        commit, dirty = "?", ""
    dirty = [line for line in dirty.splitlines() if line.strip()]
    return {
        "cpu": cpu, "cores": os.cpu_count(), "usable_cores": len(os.sched_getaffinity(0)),
        "gl_renderer": ctx.info["GL_RENDERER"], "gl_version": ctx.info["GL_VERSION"],
        "gl_vendor": ctx.info["GL_VENDOR"], "python": platform.python_version(),
        "os": platform.platform(), "versions": versions,
        "commit": commit + (f" plus uncommitted changes to {', '.join(l[3:] for l in dirty)}"
                            if dirty else ""),
        "date": time.strftime("%Y-%m-%d %H:%M %Z"), "load_start": os.getloadavg(),
    }


# ---------------------------------------------------------------------------------------------
# The sections
# ---------------------------------------------------------------------------------------------

def frame_section(ctx, cfg) -> tuple[list, list, dict, dict]:
    """Frames by size x lights, phases and silhouettes by size, memory by size.

    Per size, ONE renderer of the scene with the most lights renders the first 1, 2 or 4 of
    them (`render(lights=...)`), and the plain frame, the floor and every variant take turns
    in the same rounds: every ratio is of times measured in the same minutes."""
    from shadowvol import Renderer

    width, height = cfg["size"]
    rows, phases, sil, memory = [], [], {}, {}
    for size in cfg["sizes"]:
        warm, rep = cfg["repeat"][size]
        scene = scenes.occluder_scene(size, max(cfg["lights"]), width, height)
        one = scene.lights[:1]
        t0 = time.perf_counter()
        with Renderer(scene, ctx) as r, plain.PlainFrame(ctx, scene) as pf, \
                plain.DepthFloor(ctx, pf) as depth_floor, \
                plain.MaskFloor(ctx, pf) as mask_floor, \
                plain.ImageFloor(ctx, pf) as image_floor, \
                plain.LightingFloor(ctx, pf) as lighting:
            setup = time.perf_counter() - t0
            frames.check_same_scene(r)
            r.render()          # lazily built programs, kept side quads
            fns = {"plain": pf, "depth floor": depth_floor, "mask floor": mask_floor,
                   "image floor": image_floor,
                   "lighting: lit": lighting.lit, "lighting: flat": lighting.flat,
                   "floor": lambda: r.render(shadows=False, lights=one)}
            for n in cfg["lights"]:
                lights = scene.lights[:n]
                fns[f"auto/cpu x{n}"] = lambda lights=lights: r.render(lights=lights)
                fns[f"masks/cpu x{n}"] = (lambda lights=lights:
                                          r.render(lights=lights, outputs=MASKS))
            fns["auto/gpu x1"] = lambda: r.render("auto", "gpu", lights=one)
            fns["auto/cpu x1 srgb"] = lambda: r.render(lights=one,
                                                       outputs=("image_srgb",) + MASKS)

            def culled():
                r.cull_back_faces = True
                try:
                    return r.render(lights=one)
                finally:
                    r.cull_back_faces = False
            fns["auto/cpu x1 culled"] = culled
            times = frames.interleaved(fns, rep, warm)
            frame = r.render(lights=one)
            every = r.render()   # each light's share of the covered pixels it lights
            lit_fractions = [float(lit.sum() / every.coverage.sum()) for lit in every.lit]
            rows.append({"size": size, "triangles": scenes.triangle_count(scene),
                         "setup_s": setup, "times": times,
                         "auto_zfail_casters": int(frame.zfail.sum()),
                         "casters": len(scene.objects),
                         # the covered pixels the light lights (the lighting floor's share)
                         "lit_fraction": float(frame.lit[0].sum() / frame.coverage.sum()),
                         "lit_fractions": lit_fractions})
            log(f"frames {size}: plain {times['plain']['median']:.1f} ms, auto/cpu x1 "
                f"{times['auto/cpu x1']['median']:.1f} ms, x4 "
                f"{times.get('auto/cpu x4', times['auto/cpu x1'])['median']:.1f} ms")
            prep = cfg["phase_repeat"][size]
            for s in SILHOUETTES:
                phases.append({"size": size, "method": "auto", "silhouettes": s,
                               "phases": frames.phase_times(r, "auto", s, prep, lights=one)})
            sil[size] = {"cpu": frames.cpu_silhouette_times(r, max(prep, 3), one),
                         "gpu": frames.gpu_silhouette_times(r, max(prep, 3), one)}
            memory[size] = {
                "frame_python_peak_mb": frames.python_peak_bytes(
                    lambda: r.render("auto", "cpu", lights=one)) / 2**20,
                "maxrss_mb": maxrss_mb()}
    return rows, phases, sil, memory


def objects_section(ctx, cfg) -> list:
    """Per number of casters (`scenes.many_casters_scene`): the mask-only and the full frame's
    wall time and the part of it spent outside GL calls (`frames.python_times`), CPU
    silhouettes, one light."""
    from shadowvol import Renderer

    out = []
    for count in cfg["object_counts"]:
        scene = scenes.many_casters_scene(count)
        with Renderer(scene, ctx) as r:
            row = {"objects": len(scene.objects), "triangles": scenes.triangle_count(scene)}
            for name, outputs in (("masks", MASKS), ("image + masks", ("image",) + MASKS)):
                row[name] = frames.python_times(r, cfg["object_repeat"], outputs=outputs)
        out.append(row)
        log(f"objects {row['objects']}: Python {row['masks']['python']['median']:.1f} ms "
            "a mask-only frame")
    return out


def overflow_section(ctx, cfg) -> list:
    """The stencil-overflow check on the shared meshes: the same renderer with the check on and
    off, interleaved (and the plain frame)."""
    from shadowvol import Renderer

    if scenes.models_dir() is None:
        log("overflow: the shared meshes are missing; skipped")
        return []
    width, height = cfg["size"]
    warm, rep = cfg["overflow_repeat"]
    out = []
    for name in cfg["overflow_meshes"]:
        scene = scenes.model_scene(name, width, height)
        with Renderer(scene, ctx) as r, plain.PlainFrame(ctx, scene) as pf:
            def checked(on):
                r.check_overflow = on
                return r.render()
            fns = {"plain": pf, "checked": lambda: checked(True),
                   "unchecked": lambda: checked(False)}
            raw: dict = {}
            times = frames.interleaved(fns, rep, warm, alternate=True, raw=raw)
            # checked and unchecked run next to each other in every round (in either order):
            # their per-round ratio cancels the machine's drift between rounds
            paired = [c / u for c, u in zip(raw["checked"], raw["unchecked"])]
            bounds = [v[1] for v in r._light_bounds.values() if v is not None]
            out.append({"mesh": name, "triangles": scenes.triangle_count(scene),
                        "count_bound": r.count_bound, "light_bounds": bounds, "times": times,
                        "paired_ratio": {"median": statistics.median(paired),
                                         "min": min(paired), "max": max(paired)},
                        "checks": r.count_bound >= 256 and (not bounds or max(bounds) >= 256)})
        log(f"overflow {name}: checked {times['checked']['median']:.1f} ms, unchecked "
            f"{times['unchecked']['median']:.1f} ms (bound {out[-1]['count_bound']})")
    return out


def turntable_section(ctx, cfg) -> dict:
    """36 views of the shared meshes: our masks + image per view (one renderer, the camera
    changes) against `raytrace.shadow_masks` of the same view, view by view in turn."""
    from raytrace import shadow_masks
    from shadowvol import Renderer
    from shadowvol.raster.context import make_current

    if scenes.models_dir() is None:
        log("turntable: the shared meshes are missing; skipped")
        return {}
    w, h = cfg["turntable"]["size"]
    scene = scenes.turntable_scene(w, h)
    cameras = scenes.turntable_cameras(cfg["turntable"]["views"])
    ours, ray, masks_only, differ = [], [], [], []
    with Renderer(scene, ctx) as r:
        r.render()
        shadow_masks(scene)       # warm-up: thread pool, Embree
        for cam in cameras:
            t0 = time.perf_counter()
            res = r.render(camera=cam)
            ours.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            r.render(camera=cam, outputs=MASKS)
            masks_only.append(time.perf_counter() - t0)
            view = scene.replace(camera=cam)
            t0 = time.perf_counter()
            lit, cov = shadow_masks(view)
            ray.append(time.perf_counter() - t0)
            make_current(ctx)
            differ.append(int((lit != res.lit).sum()))
        # where a view's time goes: glFinish-bracketed phases of instrumented views
        phase_runs = defaultdict(list)
        for cam in cameras[::max(1, len(cameras) // 6)]:
            sink = defaultdict(float)
            with frames._phase_clock(r, sink):
                t0 = time.perf_counter()
                r.render(camera=cam)
                phase_runs["instrumented view"].append(time.perf_counter() - t0)
            for phase in frames.PHASES:
                phase_runs[phase].append(sink[phase])
    out = {"views": len(cameras), "width": w, "height": h,
           "triangles": scenes.triangle_count(scene), "lights": len(scene.lights),
           "ours": frames.stats(ours), "ours_masks": frames.stats(masks_only),
           "raytrace": frames.stats(ray), "ours_total_s": sum(ours), "raytrace_total_s": sum(ray),
           "pixels_differing_max": max(differ), "pixels_differing_median": sorted(differ)[len(differ) // 2],
           "phases": {k: frames.stats(v) for k, v in phase_runs.items()}}
    log(f"turntable: ours {out['ours']['median']:.1f} ms/view, raytrace "
        f"{out['raytrace']['median']:.1f} ms/view")
    return out


def pyrender_section(ctx, cfg) -> list:
    from shadowvol import Renderer
    from shadowvol.raster.context import make_current

    width, height = cfg["size"]
    out = []
    for size in cfg["pyrender_sizes"]:
        warm, rep = cfg["pyrender_repeat"][size]
        for kind in ("spot", "directional"):
            scene = scenes.occluder_scene(size, kind, width, height)
            with Renderer(scene, ctx) as r, plain.PlainFrame(ctx, scene) as pf, \
                    frames.pyrender_frames(scene) as pr:
                def ours(s="cpu"):
                    make_current(ctx)
                    return r.render("auto", s)

                def plain_frame():
                    make_current(ctx)
                    return pf()
                fns = {"plain": plain_frame, "auto/cpu": ours,
                       "auto/gpu": lambda: ours("gpu"),
                       "pyrender shadowed": pr["shadowed"],
                       "pyrender unshadowed": pr["unshadowed"]}
                times = frames.interleaved(fns, rep, warm)
            make_current(ctx)
            out.append({"size": size, "triangles": scenes.triangle_count(scene), "light": kind,
                        "times": times})
            log(f"pyrender {size} {kind}: pyrender shadowed "
                f"{times['pyrender shadowed']['median']:.1f} ms, ours auto/cpu "
                f"{times['auto/cpu']['median']:.1f} ms")
    return out


# VmHWM, the peak RSS of this process's memory since exec (ru_maxrss would carry the parent's
# peak over from fork)
RSS_CHILD = """
import time
def hwm_mb():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
from benchmarks import scenes
scene = scenes.occluder_scene({size!r}, 1, 1280, 720)
base = hwm_mb()
t0 = time.perf_counter()
if {what!r} == "frame":
    from shadowvol import Renderer
    with Renderer(scene) as r:
        r.render()
else:
    from raytrace import shadow_masks
    shadow_masks(scene)
print(base, hwm_mb(), time.perf_counter() - t0)
"""


def rss_section(cfg) -> dict:
    """Peak RSS of one process that builds the scene and renders one frame, against one that
    computes the ray tracer's masks of it (each in a fresh process: the peak is monotone)."""
    out = {"size": cfg["rss_size"]}
    for what in ("frame", "masks"):
        code = RSS_CHILD.format(size=cfg["rss_size"], what=what)
        done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                              text=True, check=True)
        scene_mb, peak_mb, seconds = (float(x) for x in done.stdout.split()[-3:])
        out[what] = {"after_scene_mb": scene_mb, "peak_mb": peak_mb, "seconds": seconds}
    log(f"rss {cfg['rss_size']}: frame {out['frame']['peak_mb']:.0f} MB, masks "
        f"{out['masks']['peak_mb']:.0f} MB")
    return out


def raytrace_section(cfg) -> dict:
    import raytrace
    from shadowvol import load_scene

    width, height = cfg["size"]
    masks = []
    for size in cfg["mask_sizes"]:
        scene = scenes.occluder_scene(size, 1, width, height)
        res = bench_masks.measure(scene, cfg["mask_runs"], full=True)
        res.update(scene=f"occluders {size}", memory_python_peak_mb=frames.python_peak_bytes(
            lambda: raytrace.shadow_masks(scene, "embree")) / 2**20)
        masks.append(res)
        log(f"masks {size}: {res['masks']['median'] * 1e3:.0f} ms vs raw "
            f"{res['raw']['median'] * 1e3:.0f} ms")
    if cfg["bunny"] and bench_masks.BUNNY.is_file():
        res = bench_masks.measure(bench_masks.bunny_scene(width, height), cfg["mask_runs"],
                                  full=True)
        res["scene"] = "Stanford bunny"
        masks.append(res)
        log(f"masks bunny: {res['masks']['median'] * 1e3:.0f} ms vs raw "
            f"{res['raw']['median'] * 1e3:.0f} ms")
    w, h = cfg["whitted_size"]
    scene = load_scene(ROOT / "scenes" / "whitted.toml").replace(width=w, height=h)
    times = []
    raytrace.render(scene, progress=False)   # warm-up (thread pool, Embree build paths)
    for _ in range(cfg["whitted_runs"]):
        t0 = time.perf_counter()
        raytrace.render(scene, progress=False)
        times.append(time.perf_counter() - t0)
    log(f"whitted: {frames.stats(times)['median']:.0f} ms")
    return {"masks": masks, "whitted": {"scene": "scenes/whitted.toml", "width": w,
                                        "height": h, "max_depth": scene.max_depth,
                                        "times": frames.stats(times)}}


# ---------------------------------------------------------------------------------------------

# The other issues' benchmarks, each a module of its own (benchmarks/bench_*.py), run by this
# command in the same run and reported verbatim: (name, arguments, what it measures).  The
# ground truth's (bench_groundtruth.py) is measured in the run itself: its own section.
EXTRAS = (
    ("bench_mitsuba.py", ["--json", "{json}"],
     "mask-only frames against Mitsuba 3's llvm_ad_rgb masks (an optional peer: the bench "
     "extra) and raytrace.shadow_masks, bunny, 100k and 1M (issue: frame cost)"),
    ("bench_soft.py", ["--size", "100k"],
     "soft shadows: a rect light of N = 1, 4, 16, 64 samples against point lights, and the "
     "raster against the ray tracer's lit_count (issue: soft shadows)"),
    ("bench_batch.py", [],
     "shadowvol batch on the 36-view turntable of the shared meshes: 1 worker, 2 workers, 2 "
     "shards, Ray with 2 actors, and the machinery's overhead (issue: datasets at scale)"),
    ("bench_outlook.py", [],
     "path tracing Mrays/s against raw Embree casts, radiosity at ~1k/4k/16k patches (issue: "
     "the lecture's outlook)"),
    ("bench_viewer.py", ["--frames", "15"],
     "the viewer's frame rate on the shipped scenes, under its own Xvfb (issue: the course)"),
)
EXTRA_TIMEOUT_S = 900


def _module(script: str) -> str:
    """The module an EXTRAS script runs as: "bench_soft.py" -> "benchmarks.bench_soft"."""
    return "benchmarks." + script.removesuffix(".py")


def extras_section() -> list[dict]:
    """Run every EXTRAS script once, in this run, one after another; keep what it prints."""
    rows = []
    for script, listed, what in EXTRAS:
        # "{json}": a file the script writes its results to, kept in results.json
        json_path = Path(tempfile.mkstemp(suffix=".json")[1]) if "{json}" in listed else None
        args = [str(json_path) if a == "{json}" else a for a in listed]
        command = [sys.executable, "-m", _module(script), *args]
        log(f"extra: {script} {' '.join(args)}")
        start = time.perf_counter()
        try:
            done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True,
                                  timeout=EXTRA_TIMEOUT_S)
            output, rc = done.stdout + (done.stderr[-2000:] if done.returncode else ""), \
                done.returncode
        except subprocess.TimeoutExpired as exc:
            output, rc = f"timed out after {exc.timeout} s", None
        data = None
        if json_path is not None:
            try:
                data = json.loads(json_path.read_text() or "null")
            except (OSError, ValueError):
                data = None
            json_path.unlink(missing_ok=True)
        shown = [a for a in listed if a not in ("--json", "{json}")]
        rows.append({"script": script, "command": " ".join(["python -m", _module(script), *shown]),
                     "what": what, "seconds": time.perf_counter() - start,
                     "returncode": rc, "output": output.strip(), "results": data})
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help="a smoke run: tiny scenes and sizes, one or two repeats")
    ap.add_argument("--out", type=Path, default=None,
                    help="folder for BENCHMARKS.md, the plot and results.json (default: the "
                         "checkout for a full run: BENCHMARKS.md, docs/benchmarks.png, "
                         "benchmarks/results.json; test-output/benchmarks-quick for --quick)")
    ap.add_argument("--no-pyrender", action="store_true", help="skip the pyrender peer")
    ap.add_argument("--no-extras", action="store_true",
                    help="skip the other issues' benchmark scripts (EXTRAS; a --quick run "
                         "skips them too)")
    ap.add_argument("--report-only", type=Path, metavar="RESULTS_JSON",
                    help="measure nothing: rewrite the markdown and the plot from a run's "
                         "results.json (e.g. after editing benchmarks/OPTIMISATIONS.md)")
    args = ap.parse_args(argv)
    cfg = QUICK if args.quick else FULL
    if args.out is not None:
        paths = {"md": args.out / "BENCHMARKS.md", "png": args.out / "benchmarks.png",
                 "json": args.out / "results.json"}
    elif args.quick:
        out = ROOT / "test-output" / "benchmarks-quick"
        paths = {"md": out / "BENCHMARKS.md", "png": out / "benchmarks.png",
                 "json": out / "results.json"}
    else:
        paths = {"md": ROOT / "BENCHMARKS.md", "png": ROOT / "docs" / "benchmarks.png",
                 "json": ROOT / "benchmarks" / "results.json"}
    for p in paths.values():
        p.parent.mkdir(parents=True, exist_ok=True)

    optimisations = ROOT / "benchmarks" / "OPTIMISATIONS.md"
    history = optimisations.read_text() if optimisations.is_file() else ""
    if args.report_only:
        results = json.loads(args.report_only.read_text())
        report.write(results, paths["md"], paths["png"], history)
        log(f"rewrote {paths['md']} and {paths['png']} from {args.report_only}")
        return 0

    from shadowvol.raster.context import create_context

    command = "python -m benchmarks.run" + (" --quick" if args.quick else "") + \
              (" --no-pyrender" if args.no_pyrender else "")
    started = time.perf_counter()
    ctx = create_context()
    try:
        results = {"command": command, "quick": args.quick, "machine": machine(ctx),
                   "config": {k: v for k, v in cfg.items()}}
        frame_rows, phases, sil, memory = frame_section(ctx, cfg)
        results.update(frames=frame_rows, phases=phases, silhouettes=sil, memory=memory)
        results["overflow"] = overflow_section(ctx, cfg)
        results["objects"] = objects_section(ctx, cfg)
        results["turntable"] = turntable_section(ctx, cfg)
        results["maxrss_after_frames_mb"] = maxrss_mb()
        results["pyrender"] = [] if args.no_pyrender else pyrender_section(ctx, cfg)
        results["maxrss_after_pyrender_mb"] = maxrss_mb()
        width, height = cfg["size"]
        results["groundtruth"] = bench_groundtruth.measure(
            ctx, cfg["truth_runs"], width, height, cfg["truth_size"])
        log("ground truth: all outputs "
            f"{results['groundtruth']['raster']['+ all']['median']:.0f} ms (raster)")
    finally:
        ctx.release()
    results["rss"] = rss_section(cfg)
    results["raytrace"] = raytrace_section(cfg)
    results["extras"] = [] if args.quick or args.no_extras else extras_section()
    results["maxrss_end_mb"] = maxrss_mb()
    results["machine"]["load_end"] = os.getloadavg()
    results["wall_s"] = time.perf_counter() - started
    paths["json"].write_text(json.dumps(results, indent=1, default=str))
    report.write(results, paths["md"], paths["png"], history)
    log(f"wrote {paths['md']}, {paths['png']} and {paths['json']} "
        f"in {results['wall_s']:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
