"""The sections of a run measured in this process on one GL context: frames by size and their
phases, the Python per object, the overflow check, the turntable, pyrender, and the ray tracer's
masks and Whitted render (no GL)."""

from __future__ import annotations

import statistics
import time
from collections import defaultdict
from pathlib import Path

from . import bench_masks, frame_timing, plain, scenes
from .machine import log, maxrss_mb

ROOT = Path(__file__).resolve().parents[1]
SILHOUETTES = frame_timing.SILHOUETTES
MASKS = ("lit", "coverage")


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
            frame_timing.check_same_scene(r)
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
            times = frame_timing.interleaved(fns, rep, warm)
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
                               "phases": frame_timing.phase_times(r, "auto", s, prep, lights=one)})
            sil[size] = {"cpu": frame_timing.cpu_silhouette_times(r, max(prep, 3), one),
                         "gpu": frame_timing.gpu_silhouette_times(r, max(prep, 3), one)}
            memory[size] = {
                "frame_python_peak_mb": frame_timing.python_peak_bytes(
                    lambda: r.render("auto", "cpu", lights=one)) / 2**20,
                "maxrss_mb": maxrss_mb()}
    return rows, phases, sil, memory


def objects_section(ctx, cfg) -> list:
    """Per number of casters (`scenes.many_casters_scene`): the mask-only and the full frame's
    wall time and the part of it spent outside GL calls (`frame_timing.python_times`), CPU
    silhouettes, one light."""
    from shadowvol import Renderer

    out = []
    for count in cfg["object_counts"]:
        scene = scenes.many_casters_scene(count)
        with Renderer(scene, ctx) as r:
            row = {"objects": len(scene.objects), "triangles": scenes.triangle_count(scene)}
            for name, outputs in (("masks", MASKS), ("image + masks", ("image",) + MASKS)):
                row[name] = frame_timing.python_times(r, cfg["object_repeat"], outputs=outputs)
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
            times = frame_timing.interleaved(fns, rep, warm, alternate=True, raw=raw)
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
    from shadowvol.raster.platform.context import make_current

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
            with frame_timing._phase_clock(r, sink):
                t0 = time.perf_counter()
                r.render(camera=cam)
                phase_runs["instrumented view"].append(time.perf_counter() - t0)
            for phase in frame_timing.PHASES:
                phase_runs[phase].append(sink[phase])
    out = {"views": len(cameras), "width": w, "height": h,
           "triangles": scenes.triangle_count(scene), "lights": len(scene.lights),
           "ours": frame_timing.stats(ours), "ours_masks": frame_timing.stats(masks_only),
           "raytrace": frame_timing.stats(ray), "ours_total_s": sum(ours), "raytrace_total_s": sum(ray),
           "pixels_differing_max": max(differ),
           "pixels_differing_median": sorted(differ)[len(differ) // 2],
           "phases": {k: frame_timing.stats(v) for k, v in phase_runs.items()}}
    log(f"turntable: ours {out['ours']['median']:.1f} ms/view, raytrace "
        f"{out['raytrace']['median']:.1f} ms/view")
    return out


def pyrender_section(ctx, cfg) -> list:
    from shadowvol import Renderer
    from shadowvol.raster.platform.context import make_current

    width, height = cfg["size"]
    out = []
    for size in cfg["pyrender_sizes"]:
        warm, rep = cfg["pyrender_repeat"][size]
        for kind in ("spot", "directional"):
            scene = scenes.occluder_scene(size, kind, width, height)
            with Renderer(scene, ctx) as r, plain.PlainFrame(ctx, scene) as pf, \
                    frame_timing.pyrender_frames(scene) as pr:
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
                times = frame_timing.interleaved(fns, rep, warm)
            make_current(ctx)
            out.append({"size": size, "triangles": scenes.triangle_count(scene), "light": kind,
                        "times": times})
            log(f"pyrender {size} {kind}: pyrender shadowed "
                f"{times['pyrender shadowed']['median']:.1f} ms, ours auto/cpu "
                f"{times['auto/cpu']['median']:.1f} ms")
    return out


def raytrace_section(cfg) -> dict:
    import raytrace
    from shadowvol import load_scene

    width, height = cfg["size"]
    masks = []
    for size in cfg["mask_sizes"]:
        scene = scenes.occluder_scene(size, 1, width, height)
        res = bench_masks.measure(scene, cfg["mask_runs"], full=True)
        res.update(scene=f"occluders {size}", memory_python_peak_mb=frame_timing.python_peak_bytes(
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
    log(f"whitted: {frame_timing.stats(times)['median']:.0f} ms")
    return {"masks": masks, "whitted": {"scene": "scenes/whitted.toml", "width": w,
                                        "height": h, "max_depth": scene.max_depth,
                                        "times": frame_timing.stats(times)}}
