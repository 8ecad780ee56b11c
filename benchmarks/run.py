"""Every benchmark of shadowvol in one reproducible run; writes BENCHMARKS.md and its plot.

    python benchmarks/run.py            # the full run (~10-15 min on 2 cores / llvmpipe)
    python benchmarks/run.py --quick    # a smoke run on small scenes (seconds), into --out

What it measures (medians of several runs after warm-up, with min and max):

* shadowvol frames at 1280x720 with read-back, on the procedural scenes of `scenes` (~1k, 10k,
  100k and 1M triangles) with 1, 2 and 4 point lights: z-pass, z-fail and auto, CPU and GPU
  silhouettes; the floor (the same frame without shadow volumes, `render(shadows=False)`: same
  geometry, same context, same size, same read-back) interleaved with them;
* each phase of a frame (`frames`: glFinish-bracketed wall time), and silhouette extraction
  alone on the CPU and the GPU;
* resolution scaling, 640x360 to 2560x1440, at 100k triangles;
* pyrender 0.1.45's frame of the same scenes with and without its shadow maps (spot and
  directional light), interleaved with ours;
* raytrace masks against raw embreex casts of the same rays (`bench_masks.measure`), and a full
  Whitted render;
* peak memory: tracemalloc (Python heap, incl. numpy) per frame and the process's ru_maxrss.

The markdown is written by this script from the measured numbers, plus the hand-written
history of the optimisations (`benchmarks/OPTIMISATIONS.md`) included verbatim.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import time
from importlib import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))          # run from a checkout, installed or not
sys.path.insert(0, str(ROOT / "benchmarks"))

import bench_groundtruth  # noqa: E402
import bench_masks  # noqa: E402
import frames  # noqa: E402
import report  # noqa: E402

import scenes  # noqa: E402

FULL = dict(
    sizes=("1k", "10k", "100k", "1M"), lights=(1, 2, 4), size=(1280, 720),
    # (warm-up, timed) frames per size: fewer at 1M, where one frame takes seconds
    repeat={"1k": (2, 7), "10k": (2, 7), "100k": (2, 11), "1M": (1, 3)},
    phase_repeat={"1k": 5, "10k": 5, "100k": 5, "1M": 2},
    resolutions=((640, 360), (1280, 720), (1920, 1080), (2560, 1440)), resolution_size="100k",
    resolution_repeat=(2, 7),
    pyrender_sizes=("1k", "10k", "100k", "1M"),
    pyrender_repeat={"1k": (2, 7), "10k": (2, 7), "100k": (2, 5), "1M": (1, 2)},
    mask_sizes=("100k", "1M"), mask_runs=7, bunny=True,
    whitted_size=(1280, 720), whitted_runs=3,
    truth_size="100k", truth_runs=7,
)
QUICK = dict(
    sizes=("1k",), lights=(1, 2), size=(320, 180),
    repeat={"1k": (1, 2)}, phase_repeat={"1k": 1},
    resolutions=((160, 90), (320, 180)), resolution_size="1k", resolution_repeat=(1, 2),
    pyrender_sizes=("1k",), pyrender_repeat={"1k": (1, 2)},
    mask_sizes=("1k",), mask_runs=1, bunny=False,
    whitted_size=(160, 90), whitted_runs=1,
    truth_size="1k", truth_runs=1,
)
VARIANTS = [(m, s) for s in frames.SILHOUETTES for m in frames.METHODS]


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
                "matplotlib"):
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
    them (`render(lights=...)`), and all light counts and variants take turns in the same
    rounds: the cost of a further light is then measured against a floor timed in the same
    rounds, not in another minute with another load."""
    from shadowvol.raster.renderer import Renderer

    width, height = cfg["size"]
    rows, phases, sil, memory = [], [], {}, {}
    for size in cfg["sizes"]:
        warm, rep = cfg["repeat"][size]
        scene = scenes.occluder_scene(size, max(cfg["lights"]), width, height)
        t0 = time.perf_counter()
        with Renderer(scene, ctx) as r:
            setup = time.perf_counter() - t0
            frames.check_same_scene(r)
            sets = {n: scene.lights[:n] for n in cfg["lights"]}
            fns = {}
            for n, lights in sets.items():
                fns[n, "floor"] = lambda lights=lights: r.render(shadows=False, lights=lights)
                for m, s in VARIANTS:
                    fns[n, f"{m}/{s}"] = (lambda m=m, s=s, lights=lights:
                                          r.render(m, s, lights=lights))
            times = frames.interleaved(fns, rep, warm)
            for n, lights in sets.items():
                row_times = {key: t for (k, key), t in times.items() if k == n}
                rows.append({"size": size, "triangles": scenes.triangle_count(scene),
                             "lights": n, "setup_s": setup, "times": row_times,
                             "auto_zfail_casters": int(r.render("auto", lights=lights)
                                                       .zfail.sum()),
                             "casters": len(scene.objects)})
                log(f"frames {size} x{n}: floor {row_times['floor']['median']:.1f} ms, "
                    f"auto/cpu {row_times['auto/cpu']['median']:.1f} ms")
            one = sets[min(sets)]
            prep = cfg["phase_repeat"][size]
            for m, s in VARIANTS:
                phases.append({"size": size, "method": m, "silhouettes": s,
                               "phases": frames.phase_times(r, m, s, prep, lights=one)})
            sil[size] = {"cpu": frames.cpu_silhouette_times(r, max(prep, 3), one),
                         "gpu": frames.gpu_silhouette_times(r, max(prep, 3), one)}
            memory[size] = {
                "frame_python_peak_mb": frames.python_peak_bytes(
                    lambda: r.render("auto", "cpu", lights=one)) / 2**20,
                "maxrss_mb": maxrss_mb()}
    return rows, phases, sil, memory


def resolution_section(ctx, cfg) -> list:
    from shadowvol.raster.renderer import Renderer

    out = []
    warm, rep = cfg["resolution_repeat"]
    for width, height in cfg["resolutions"]:
        scene = scenes.occluder_scene(cfg["resolution_size"], 1, width, height)
        with Renderer(scene, ctx) as r:
            fns = {"floor": lambda: r.render(shadows=False)}
            for m, s in VARIANTS:
                fns[f"{m}/{s}"] = (lambda m=m, s=s: r.render(m, s))
            times = frames.interleaved(fns, rep, warm)
        out.append({"width": width, "height": height, "times": times})
        log(f"resolution {width}x{height}: floor {times['floor']['median']:.1f} ms, "
            f"auto/cpu {times['auto/cpu']['median']:.1f} ms")
    return out


def pyrender_section(ctx, cfg) -> list:
    from shadowvol.raster.context import make_current
    from shadowvol.raster.renderer import Renderer

    width, height = cfg["size"]
    out = []
    for size in cfg["pyrender_sizes"]:
        warm, rep = cfg["pyrender_repeat"][size]
        for kind in ("spot", "directional"):
            scene = scenes.occluder_scene(size, kind, width, height)
            with Renderer(scene, ctx) as r, frames.pyrender_frames(scene) as pr:
                fns = {"floor": lambda: r.render(shadows=False),
                       "auto/cpu": lambda: r.render("auto", "cpu"),
                       "auto/gpu": lambda: r.render("auto", "gpu"),
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


def raytrace_section(cfg) -> dict:
    from raytrace import whitted
    from raytrace.masks import shadow_masks
    from shadowvol.scenefile import load_scene

    width, height = cfg["size"]
    masks = []
    for size in cfg["mask_sizes"]:
        scene = scenes.occluder_scene(size, 1, width, height)
        res = bench_masks.measure(scene, cfg["mask_runs"], full=True)
        res.update(scene=f"occluders {size}", memory_python_peak_mb=frames.python_peak_bytes(
            lambda: shadow_masks(scene, "embree")) / 2**20)
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
    whitted.render(scene, progress=False)   # warm-up (thread pool, Embree build paths)
    for _ in range(cfg["whitted_runs"]):
        t0 = time.perf_counter()
        whitted.render(scene, progress=False)
        times.append(time.perf_counter() - t0)
    log(f"whitted: {frames.stats(times)['median']:.0f} ms")
    return {"masks": masks, "whitted": {"scene": "scenes/whitted.toml", "width": w,
                                        "height": h, "max_depth": scene.max_depth,
                                        "times": frames.stats(times)}}


# ---------------------------------------------------------------------------------------------

def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help="a smoke run: tiny scenes and sizes, one or two repeats")
    ap.add_argument("--out", type=Path, default=None,
                    help="folder for BENCHMARKS.md, the plot and results.json (default: the "
                         "checkout for a full run: BENCHMARKS.md, docs/benchmarks.png, "
                         "benchmarks/results.json; test-output/benchmarks-quick for --quick)")
    ap.add_argument("--no-pyrender", action="store_true", help="skip the pyrender peer")
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

    command = "python benchmarks/run.py" + (" --quick" if args.quick else "") + \
              (" --no-pyrender" if args.no_pyrender else "")
    started = time.perf_counter()
    ctx = create_context()
    try:
        results = {"command": command, "quick": args.quick, "machine": machine(ctx),
                   "config": {k: v for k, v in cfg.items()}}
        frame_rows, phases, sil, memory = frame_section(ctx, cfg)
        results.update(frames=frame_rows, phases=phases, silhouettes=sil, memory=memory)
        results["resolution"] = resolution_section(ctx, cfg)
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
    results["raytrace"] = raytrace_section(cfg)
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
