"""BENCHMARKS.md and its plot, written from one run's results (see `run`)."""

from __future__ import annotations

import os
import statistics
from pathlib import Path

from . import bench_groundtruth

HEADLINE_SIZE = "100k"


def _ms(s: dict) -> str:
    return f"{s['median']:.1f} ({s['min']:.1f}–{s['max']:.1f})"


def _met(ok: bool | None) -> str:
    return "—" if ok is None else ("**met**" if ok else "not met")


def _find(rows, **key):
    for r in rows:
        if all(r.get(k) == v for k, v in key.items()):
            return r
    return None


def _tri(results, size) -> int:
    return _find(results["frames"], size=size)["triangles"]


def _med(row, key) -> float:
    return row["times"][key]["median"]


def further_light(row, n: int, key: str = "auto/cpu") -> float:
    """ms per further light, 1 -> n lights."""
    return (_med(row, f"{key} x{n}") - _med(row, f"{key} x1")) / (n - 1)


def _overflow_cost(o: dict) -> float:
    """The check's cost as a fraction of a frame: the median over rounds of checked /
    unchecked, each pair timed next to each other (the ratio of the medians where a run did not
    record pairs)."""
    if "paired_ratio" in o:
        return o["paired_ratio"]["median"] - 1
    return _med(o, "checked") / _med(o, "unchecked") - 1


def _mitsuba(results: dict) -> dict | None:
    """bench_mitsuba.py's results in this run's extras, if it ran."""
    for row in results.get("extras", []):
        if row["script"] == "bench_mitsuba.py":
            return row.get("results")
    return None


def mask_bound_ms(ms: dict) -> float | None:
    """Mask floor + volume pass (medians, ms) of one `bench_mitsuba.py` scene's times: the least
    any exact mask-only shadow-volume frame of it costs here (depth floor + volume pass in a
    result from before the mask floor was measured); None without them."""
    floor = ms.get("mask floor", ms.get("depth floor"))
    if floor is None or "volume pass" not in ms:
        return None
    return floor["median"] + ms["volume pass"]["median"]


def lower_bounds(results: dict) -> list[dict]:
    """Per size: the plain frame, the depth, mask and image floors (interleaved rounds) and
    the CPU-silhouette volume pass (instrumented frames), medians in ms, and the bounds they
    give (see write)."""
    out = []
    for row in results["frames"]:
        if "depth floor" not in row["times"]:
            continue
        phase = _find(results["phases"], size=row["size"], silhouettes="cpu")
        if phase is None:
            continue
        pl, floor = _med(row, "plain"), _med(row, "depth floor")
        vol = phase["phases"]["volume pass"]["median"]
        image = _med(row, "image floor") if "image floor" in row["times"] else None
        masks = _med(row, "mask floor") if "mask floor" in row["times"] else None
        # the lighting arithmetic of the covered pixels, counted only for the share the light
        # lights (an exact frame may skip the others), and never below 0
        per_pixel = (max(_med(row, "lighting: lit") - _med(row, "lighting: flat"), 0.0)
                     if "lighting: lit" in row["times"] else None)
        lighting = None if per_pixel is None else per_pixel * row.get("lit_fraction", 1.0)
        # each further light: its volume pass, and its lighting where it lights (the
        # further lights' mean share; a run that did not record the shares: the volume
        # pass alone)
        shares = row.get("lit_fractions", [])[1:]
        further_lighting = (per_pixel * statistics.fmean(shares)
                            if shares and per_pixel is not None else 0.0)
        out.append({"size": row["size"], "triangles": row["triangles"], "plain": pl,
                    "depth_floor": floor, "volume": vol, "bound": (floor + vol) / pl,
                    "image_floor": image, "lighting": lighting, "mask_floor": masks,
                    "mask_bound": None if masks is None else (masks + vol) / pl,
                    "image_bound": (None if image is None or lighting is None
                                    else (image + vol + lighting) / pl),
                    "limit": 2.0 if row["size"] == "1k" else 1.5,
                    "further_lighting": further_lighting,
                    "further": (vol + further_lighting) / pl,
                    "ours": _med(row, "auto/cpu x1") / pl})
    return out


def headline(results: dict) -> list[tuple[str, float | None, str, bool | None]]:
    """(what, value, target, met) rows, the issue's targets."""
    out = []
    frames = results["frames"]
    for size in ("100k", "1M", "1k"):
        row = _find(frames, size=size)
        if row is None:
            continue
        r = _med(row, "auto/cpu x1") / _med(row, "plain")
        limit = 2.0 if size == "1k" else 1.5
        out.append((f"{size}, 1 light: shadowed frame (auto, CPU) / plain frame", r,
                    f"≤ {limit:g}", r <= limit))
    for size in ("100k", "1M", "1k"):
        row = _find(frames, size=size)
        if row is None or "auto/cpu x4" not in row["times"]:
            continue
        r = further_light(row, 4) / _med(row, "plain")
        out.append((f"{size}: each further light (1 → 4) / one plain frame", r, "≤ 0.3",
                    r <= 0.3))
    row = _find(frames, size="100k")
    if row is not None:
        r = _med(row, "masks/cpu x1") / _med(row, "plain")
        out.append(("100k: mask-only frame (lit + coverage) / plain frame", r, "≤ 1.2",
                    r <= 1.2))
    for o in results.get("overflow", []):
        r = _overflow_cost(o)
        out.append((f"{o['mesh']}: overflow check's cost / frame", r, "≤ 0.05", r <= 0.05))
    t = results.get("turntable") or {}
    if t:
        r = t["raytrace"]["median"] / t["ours"]["median"]
        out.append((f"turntable ({t['views']} views): raytrace.shadow_masks / ours (masks + "
                    f"image) per view — speed-up", r, "≥ 3", r >= 3.0))
    rss = results.get("rss")
    if rss:
        r = rss["frame"]["peak_mb"] / rss["masks"]["peak_mb"]
        out.append((f"{rss['size']}: peak RSS of a frame / of the ray tracer's masks", r,
                    "≤ 1.2", r <= 1.2))
    for p in results.get("pyrender", []):
        if p["size"] == HEADLINE_SIZE:
            r = _med(p, "pyrender shadowed") / _med(p, "auto/cpu")
            out.append((f"{p['size']}, 1 {p['light']} light: pyrender shadow-mapped frame / "
                        f"ours (auto, CPU) — speed-up", r, "≥ 15", r >= 15.0))
    return out


def write(results: dict, md_path: Path, png_path: Path, history: str) -> None:
    plot(results, png_path)
    m = results["machine"]
    L = []
    add = L.append
    add("# Benchmarks")
    add("")
    add("Written by `benchmarks/run.py` from one run; do not edit by hand (the optimisation "
        "history at the end is `benchmarks/OPTIMISATIONS.md`, included verbatim).")
    add("")
    add("```bash")
    add(results["command"])
    add("```")
    add("")
    add(f"- **Machine**: {m['cpu']}, {m['cores']} cores ({m['usable_cores']} usable); "
        f"{m['os']}")
    add(f"- **GL**: {m['gl_renderer']} — {m['gl_version']} ({m['gl_vendor']}), headless EGL")
    add(f"- **Versions**: Python {m['python']}, " +
        ", ".join(f"{k} {v}" for k, v in m["versions"].items()))
    add(f"- **Code**: commit {m['commit']}; run {m['date']}, {results['wall_s']:.0f} s wall")
    ls, le = m["load_start"], m["load_end"]
    add(f"- **Load** (1/5/15-min load average; other sessions share the 2 cores): at the start "
        f"{ls[0]:.2f} / {ls[1]:.2f} / {ls[2]:.2f}, at the end {le[0]:.2f} / {le[1]:.2f} / "
        f"{le[2]:.2f}.  Timings interleave the variants they compare round by round, so load "
        f"slows all of them alike; absolute times are noisier than ratios.")
    add("- **Clocks**: a frame is the wall time of `Renderer.render(...)`, which returns after "
        "reading back what was asked for (default: the linear RGB32F image, every light's lit "
        "bit and the coverage in one R32F read), so all GL work is inside it; the plain frame "
        "(`benchmarks/plain.py`) returns after its RGBA8 read-back.  Phases are "
        "glFinish-bracketed wall time (llvmpipe renders on flush), from separate instrumented "
        "frames.  Times are milliseconds: median (min–max).")
    add("- **Scenes** (`benchmarks/scenes.py`): a 14 x 14 floor and seeded icospheres "
        "(closed meshes) under the same camera; 1, 2 or 4 point lights; the pyrender "
        "comparison uses one spot (45°) or one directional light, since pyrender has no "
        "point-light shadows.")
    if results["quick"]:
        add("- **QUICK RUN**: tiny sizes and one or two repeats — a smoke test, not numbers to "
            "quote.")
    add("")
    add("![benchmarks](" + os.path.relpath(png_path, md_path.parent) + ")")
    add("")

    add("## Headline ratios and targets")
    add("")
    add("| ratio | value | target | |")
    add("|---|---:|---|---|")
    for what, value, target, ok in headline(results):
        add(f"| {what} | {value:.2f} | {target} | {_met(ok)} |")
    add("")
    mitsuba = _mitsuba(results)
    if mitsuba is None or "skipped" in mitsuba:
        add("Mitsuba 3 (`llvm_ad_rgb`) is an optional peer the issue names (`pip install "
            "'.[bench]'`); it was not installed for this run and is not timed.")
    else:
        add("Mask-only frames against Mitsuba 3's `llvm_ad_rgb` masks of the same scenes "
            "(`bench_mitsuba.py`, below: its own interleaved rounds, warm kernels).  **bound** "
            "= mask floor + volume pass of the same scene, measured there too: the least GL "
            "work of any exact mask-only shadow-volume frame of it (see \"What no exact "
            "shadow-volume frame can go below here\"); where it is not below Mitsuba's time, "
            "no mask-only frame by shadow volumes can beat Mitsuba on this machine.")
        add("")
        add("| scene | ours, masks only (ms) | Mitsuba 3 (ms) | ours / Mitsuba | target | | "
            "bound (ms) | bound / Mitsuba | bound proves it out of reach |")
        add("|---|---:|---:|---:|---|---|---:|---:|---|")
        for sc in mitsuba["scenes"]:
            if "skipped" in sc:
                continue
            ours, peer = sc["ms"]["ours, masks only"], sc["ms"]["Mitsuba 3"]
            r = ours["median"] / peer["median"]
            bound = " | | |"
            b = mask_bound_ms(sc["ms"])
            if b is not None:
                bound = (f" {b:.1f} | {b / peer['median']:.2f} | "
                         f"{'yes' if b >= peer['median'] else 'no'} |")
            add(f"| {sc['scene']} ({sc['triangles']:,} triangles) | {_ms(ours)} | "
                f"{_ms(peer)} | {r:.2f} | < 1 | {_met(r < 1)} |{bound}")
        cpu_rows = [sc for sc in mitsuba["scenes"] if "cpu_ms" in sc]
        if cpu_rows:
            add("")
            add("CPU time a frame costs, the same scenes (`bench_mitsuba.cpu_per_frame`: the "
                "process's CPU time over all its threads, during the call and in the 100 ms "
                "after it returns, each call from a settled machine; ms, median (min–max)). "
                "Not a target: what a frame leaves the rest of the machine, e.g. the other "
                "jobs of a batch.  Dr.Jit's workers go on running after Mitsuba's call has "
                "returned the masks (they spin before they sleep): the frame's wall time above "
                "does not show that work.")
            add("")
            add("| scene | ours: during | ours: after | ours: total | Mitsuba 3: during | "
                "Mitsuba 3: after | Mitsuba 3: total | ours / Mitsuba (total) |")
            add("|---|---:|---:|---:|---:|---:|---:|---:|")
            for sc in cpu_rows:
                o, m = sc["cpu_ms"]["ours, masks only"], sc["cpu_ms"]["Mitsuba 3"]
                ot = o["during"]["median"] + o["after"]["median"]
                mt = m["during"]["median"] + m["after"]["median"]
                add(f"| {sc['scene']} | {_ms(o['during'])} | {_ms(o['after'])} | {ot:.1f} | "
                    f"{_ms(m['during'])} | {_ms(m['after'])} | {mt:.1f} | {ot / mt:.2f} |")
    add("")

    size_wh = "{}x{}".format(*results["config"]["size"])
    add(f"## Frames at {size_wh}")
    add("")
    add("Whole frame with read-back, ms, one interleaved set of rounds per size.  **plain** = "
        "a plain moderngl frame of the same triangles (`benchmarks/plain.py`: one indexed "
        "draw, back-face culling, Blinn-Phong, RGBA8 read-back); **floor** = ours without "
        "shadow volumes (`shadows=False`); **auto/cpu xN** = the shadowed frame with N point "
        "lights (image + lit + coverage); **masks** = `outputs=(\"lit\", \"coverage\")`; "
        "**srgb** = the 8-bit sRGB image from the GPU + masks instead of the float image; "
        "**culled** = with the opt-in back-face culling (`Renderer.cull_back_faces`); "
        "**depth floor** = the least GL work of any exact frame of the same triangles "
        "(`plain.DepthFloor`: one indexed draw, no culling, depth only, glFinish); **mask "
        "floor** = the same draw also storing one byte of bits, read back (`plain.MaskFloor`: "
        "the least of any exact mask-only frame); **image floor** = the same draw also "
        "storing a float colour and the bits, and both read back (`plain.ImageFloor`); "
        "**lighting: lit / flat** = a depth draw and one full-screen "
        "pass over the covered pixels with and without the plain frame's Blinn-Phong "
        "(`plain.LightingFloor`: their difference is the lighting arithmetic).")
    add("")
    keys = list(results["frames"][0]["times"])
    add("| triangles | " + " | ".join(keys) + " | setup (s) |")
    add("|---:|" + "---:|" * (len(keys) + 1))
    for row in results["frames"]:
        add(f"| {row['triangles']:,} | " + " | ".join(_ms(row["times"][k]) for k in keys) +
            f" | {row['setup_s']:.1f} |")
    add("")
    add("Ratios (medians): to the plain frame, to the floor, and each further light in plain "
        "frames.")
    add("")
    add("| triangles | shadowed / plain | shadowed / floor | floor / plain | masks / plain | "
        "GPU sil. / plain | culled / plain | further light (1→2) / plain | (1→4) / plain | "
        "masks further light (1→4) / plain |")
    add("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for row in results["frames"]:
        pl = _med(row, "plain")
        x2 = further_light(row, 2) / pl if "auto/cpu x2" in row["times"] else float("nan")
        x4 = further_light(row, 4) / pl if "auto/cpu x4" in row["times"] else float("nan")
        m4 = (further_light(row, 4, "masks/cpu") / pl if "masks/cpu x4" in row["times"]
              else float("nan"))
        add(f"| {row['triangles']:,} | {_med(row, 'auto/cpu x1') / pl:.2f} | "
            f"{_med(row, 'auto/cpu x1') / _med(row, 'floor'):.2f} | "
            f"{_med(row, 'floor') / pl:.2f} | {_med(row, 'masks/cpu x1') / pl:.2f} | "
            f"{_med(row, 'auto/gpu x1') / pl:.2f} | {_med(row, 'auto/cpu x1 culled') / pl:.2f} | "
            f"{x2:.2f} | {x4:.2f} | {m4:.2f} |")
    add("")

    bounds = lower_bounds(results)
    if bounds:
        add("### What no exact shadow-volume frame can go below here")
        add("")
        add("Any exact shadowed frame rasterises every triangle without back-face culling "
            "(culling is not exact in float32: `methods.cullable`) and counts each light's "
            "volumes in the stencil.  So it costs at least **depth floor + volume pass** "
            "(the volume pass of the phases below: CPU silhouettes, halved and clipped), "
            "before any shading or read-back, and each further light at least one volume "
            "pass, and in a frame that returns the image also that light's lighting where it "
            "lights (**further lighting**: the lighting below per covered pixel, times the "
            "further lights' mean share of the covered pixels they light).  A frame that returns the masks alone also stores and reads back the bits "
            "of every pixel: at least **mask floor + volume pass** (`plain.MaskFloor`: the "
            "depth floor's draw also writing one byte a pixel, cleared, then the bytes read "
            "back; the byte is written in that one draw because whether a pixel can be lit "
            "depends on its visible triangle's side toward the light, known only to the "
            "fragment that wins the depth test, and a second or split draw would change the "
            "depth ties).  A frame that returns the image and the masks (the shadowed targets' "
            "frame) also stores a float colour and the bits of every pixel, reads them back "
            "and lights every covered pixel: at least **image floor + volume pass + "
            "lighting** (`plain.ImageFloor`: the depth floor's draw also writing a constant "
            "RGBA32F colour and one byte of bits, both cleared, then the RGB float32 image "
            "and the bytes read back; **lighting**: the plain frame's own Blinn-Phong for one "
            "light once per covered pixel, the difference of two full-screen passes that "
            "differ only by it (`plain.LightingFloor`), times the share of the covered pixels "
            "the light lights in our frame).  Where a bound already exceeds a "
            "target, no implementation of shadow volumes meets it on this machine; where it "
            "does not, the gap between the bound and our frame is what is left to win "
            "(the rest of the shading, synchronisations, Python).")
        add("")
        add("| triangles | plain | depth floor | mask floor | image floor | lighting | volume "
            "pass | bound: (depth floor + volume pass) / plain | bound for masks alone: (mask "
            "floor + volume pass) / plain | bound for image + masks: (image floor + volume "
            "pass + lighting) / plain | shadowed target | bound proves it out of reach | "
            "further lighting | bound for each further light: (volume pass + further "
            "lighting) / plain | further-light target out of reach | ours / plain |")
        add("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---|---:|")
        for b in bounds:
            image_bound = b["bound"] if b["image_bound"] is None else b["image_bound"]
            image_text = "–" if b["image_floor"] is None else f"{b['image_floor']:.1f}"
            mask_text = "–" if b["mask_floor"] is None else f"{b['mask_floor']:.1f}"
            mask_bound = "–" if b["mask_bound"] is None else f"{b['mask_bound']:.2f}"
            lighting_text = "–" if b["lighting"] is None else f"{b['lighting']:.1f}"
            bound_text = "–" if b["image_bound"] is None else f"{b['image_bound']:.2f}"
            add(f"| {b['triangles']:,} | {b['plain']:.1f} | {b['depth_floor']:.1f} | "
                f"{mask_text} | {image_text} | {lighting_text} | {b['volume']:.1f} | "
                f"{b['bound']:.2f} | {mask_bound} | {bound_text} | ≤ {b['limit']:g} | "
                f"{'yes' if image_bound > b['limit'] else 'no'} | "
                f"{b['further_lighting']:.1f} | "
                f"{b['further']:.2f} | {'yes' if b['further'] > 0.3 else 'no'} | "
                f"{b['ours']:.2f} |")
        add("")
        mask = _find(bounds, size="100k")
        if mask:
            b = mask["bound"] if mask["mask_bound"] is None else mask["mask_bound"]
            add(f"Mask-only frames at 100k: bound {b:.2f} plain frames, against a target of "
                f"≤ 1.2: {'out of reach' if b > 1.2 else 'not ruled out by the bound'}.")
            add("")

    add("## Phases (one light)")
    add("")
    add("glFinish-bracketed wall time per phase, ms, median (min–max) of instrumented frames "
        "(auto method).  CPU silhouettes are kept while the light does not move, so after the "
        "first frame their phase is the look-up only; with GPU silhouettes the silhouettes run "
        "inside the volume pass (geometry shader).")
    add("")
    names = [n for n in results["phases"][0]["phases"]]
    add("| triangles | silhouettes | " + " | ".join(names) + " |")
    add("|---:|---|" + "---:|" * len(names))
    for p in results["phases"]:
        add(f"| {_tri(results, p['size']):,} | {p['silhouettes']} | " +
            " | ".join(_ms(p["phases"][n]) for n in names) + " |")
    add("")
    add("Silhouette extraction alone, all casters, one light: CPU = signs, multiplicities and "
        "side-quad triangles in numpy (no upload; what a moving light pays per frame), GPU = "
        "the edge records through the geometry shader with rasterizer discard "
        "(glFinish-bracketed).")
    add("")
    add("| triangles | CPU (ms) | GPU (ms) | shadowed frame auto/cpu (ms) | faster |")
    add("|---:|---:|---:|---:|---|")
    for size, s in results["silhouettes"].items():
        row = _find(results["frames"], size=size)
        add(f"| {_tri(results, size):,} | {_ms(s['cpu'])} | {_ms(s['gpu'])} | "
            f"{_ms(row['times']['auto/cpu x1'])} | "
            f"{'CPU' if s['cpu']['median'] < s['gpu']['median'] else 'GPU'} |")
    add("")

    if results.get("overflow"):
        add("## The stencil-overflow check on real meshes")
        add("")
        add("Each shared mesh on a floor, one point light, the same renderer with "
            "`check_overflow` on and off, interleaved (25 rounds, every other one in reverse "
            "order, so checked and unchecked always run next to each other).  The cost of the "
            "check is the median over the rounds of checked / unchecked − 1 (min–max over the "
            "rounds beside it); the ratio of the two medians is shown too.  The re-check (one saturating volume "
            "pass per light and a stencil read) runs when the scene's bound reaches 256 and, "
            "from a light's second frame on, only when that light's bound "
            "(`overflow.light_bound`) does too.")
        add("")
        add("| mesh | triangles | scene bound | light bound | re-check after the first frame | "
            "plain | checked | unchecked | ratio of the medians − 1 | cost of the check "
            "(per-round) |")
        add("|---|---:|---:|---:|---|---:|---:|---:|---:|---:|")
        for o in results["overflow"]:
            lb = o.get("light_bounds")
            lb_text = ", ".join(f"{b:,}" for b in lb) if lb else "not recorded"
            add(f"| {o['mesh']} | {o['triangles']:,} | {o['count_bound']:,} | {lb_text} | "
                f"{('yes' if o['checks'] else 'no') if lb is not None else 'not recorded'} | "
                f"{_ms(o['times']['plain'])} | "
                f"{_ms(o['times']['checked'])} | {_ms(o['times']['unchecked'])} | "
                f"{(_med(o, 'checked') / _med(o, 'unchecked') - 1) * 100:+.0f}% | "
                f"{_overflow_cost(o) * 100:+.0f}%" +
                (f" ({(o['paired_ratio']['min'] - 1) * 100:+.0f}% to "
                 f"{(o['paired_ratio']['max'] - 1) * 100:+.0f}%)" if "paired_ratio" in o
                 else "") + " |")
        add("")

    objects = results.get("objects") or []
    if objects:
        add("## Python a frame against the number of objects")
        add("")
        add("Frames of a floor and N small closed casters (`scenes.many_casters_scene`: "
            "icosahedra, 20 triangles each, at 64x48 so the draws are small), one point "
            "light, CPU silhouettes: the whole frame and its wall time outside the GL calls "
            "that can wait for the GL (draws, clears, reads, glFinish: "
            "`frames.python_times`), ms, median (min–max).  The draws are runs of "
            "triangles, not objects; what is left per object is numpy over every object's "
            "box (the z-fail choice, the overflow check's slack).")
        add("")
        add("| objects | triangles | masks: frame | masks: Python | image + masks: frame | "
            "image + masks: Python |")
        add("|---:|---:|---:|---:|---:|---:|")
        for row in objects:
            add(f"| {row['objects']:,} | {row['triangles']:,} | "
                f"{_ms(row['masks']['frame'])} | {_ms(row['masks']['python'])} | "
                f"{_ms(row['image + masks']['frame'])} | "
                f"{_ms(row['image + masks']['python'])} |")
        if len(objects) > 1:
            a, b = objects[0], objects[-1]
            per = ((b["masks"]["python"]["median"] - a["masks"]["python"]["median"])
                   / (b["objects"] - a["objects"]) * 1e3)
            add("")
            add(f"Python a mask-only frame per further object ({a['objects']:,} → "
                f"{b['objects']:,}): {per:.2f} µs.")
        add("")

    t = results.get("turntable") or {}
    if t:
        add("## Turntable")
        add("")
        add(f"{t['views']} views at {t['width']}x{t['height']} of the five shared meshes on a "
            f"floor ({t['triangles']:,} triangles), {t['lights']} point lights; per view, in "
            f"turn: our frame (one renderer, `render(camera=...)`, image + lit + coverage), our "
            f"mask-only frame, and `raytrace.shadow_masks` of the same view (Embree, BVH "
            f"built per call: the masks' frame is the eye's).")
        add("")
        add("| | per view (ms) | all views (s) |")
        add("|---|---:|---:|")
        add(f"| ours, masks + image | {_ms(t['ours'])} | {t['ours_total_s']:.2f} |")
        add(f"| ours, masks only | {_ms(t['ours_masks'])} | |")
        add(f"| raytrace.shadow_masks | {_ms(t['raytrace'])} | {t['raytrace_total_s']:.2f} |")
        add("")
        add(f"Speed-up {t['raytrace']['median'] / t['ours']['median']:.2f}x (masks + image), "
            f"{t['raytrace']['median'] / t['ours_masks']['median']:.2f}x (masks only); lit "
            f"pixels differing between the two per view: median "
            f"{t['pixels_differing_median']}, max {t['pixels_differing_max']} (mask edges).")
        add("")
        ph = t.get("phases")
        if ph:
            names = list(ph)
            add("Where a view's time goes (glFinish-bracketed phases of "
                f"{ph[names[0]]['n']} instrumented views, ms; the volume pass is all "
                f"{t['lights']} lights'):")
            add("")
            add("| " + " | ".join(names) + " |")
            add("|" + "---:|" * len(names))
            add("| " + " | ".join(_ms(ph[n]) for n in names) + " |")
            add("")
            need = t["raytrace"]["median"] / 3.0
            vol = ph["volume pass"]["median"]
            add(f"A 3x speed-up needs a view in {need:.1f} ms; the volume passes alone take "
                f"{vol:.1f} ms and the geometry pass {ph['geometry pass']['median']:.1f} ms "
                f"(the meshes are open or have holes, so their side quads cannot be halved "
                f"and each silhouette loop's quads fill the screen down to the floor).")
            add("")

    if results.get("pyrender"):
        add("## pyrender 0.1.45, the same scenes")
        add("")
        add("pyrender's `OffscreenRenderer.render` (4x multisampled; reads colour and depth "
            "back) with `SHADOWS_SPOT | SHADOWS_DIRECTIONAL` or without, on its own EGL "
            "context, interleaved with ours and the plain frame.  Speed-up = pyrender "
            "shadowed / ours.")
        add("")
        add("| triangles | light | plain | ours auto/cpu | ours auto/gpu | pyrender "
            "unshadowed | pyrender shadowed | speed-up (cpu) | speed-up (gpu) |")
        add("|---:|---|---:|---:|---:|---:|---:|---:|---:|")
        for p in results["pyrender"]:
            t_ = p["times"]
            add(f"| {p['triangles']:,} | {p['light']} | {_ms(t_['plain'])} | "
                f"{_ms(t_['auto/cpu'])} | {_ms(t_['auto/gpu'])} | "
                f"{_ms(t_['pyrender unshadowed'])} | {_ms(t_['pyrender shadowed'])} | "
                f"{_med(p, 'pyrender shadowed') / _med(p, 'auto/cpu'):.1f}x | "
                f"{_med(p, 'pyrender shadowed') / _med(p, 'auto/gpu'):.1f}x |")
        add("")

    add("## Ray tracer")
    add("")
    add("`raytrace.shadow_masks` on a prebuilt Embree backend against raw embreex casts of the "
        "same rays (primary INTERSECT + shadow OCCLUDED where n·l > 0, float32, the same "
        "threads), interleaved (`benchmarks/bench_masks.py`); one point light.  Ratio = "
        "raw time / masks time (throughput of the masks relative to raw Embree).  Pixels "
        "differing: where the raw rays' verdict differs from the masks' — the raw shadow rays "
        "are built outside the clock the way the masks build them (the segment from the hit "
        "point to the light, shortened by the masks' margins), so this is a check that both "
        "cast the same rays, and should be 0 or a few pixels where float32 and float64 decide "
        "n·l > 0 differently.")
    add("")
    add("| scene | triangles | rays | masks (ms) | Mrays/s | raw Embree (ms) | Mrays/s | "
        "ratio | BVH build (ms) | masks incl. build (ms) | pixels differing |")
    add("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in results["raytrace"]["masks"]:
        rays = r["primary_rays"] + r["shadow_rays"]
        mk, raw = r["masks"]["median"], r["raw"]["median"]
        add(f"| {r['scene']} | {r['triangles']:,} | {rays:,} | "
            f"{mk * 1e3:.0f} ({r['masks']['min'] * 1e3:.0f}–{r['masks']['max'] * 1e3:.0f}) | "
            f"{rays / mk / 1e6:.1f} | "
            f"{raw * 1e3:.0f} ({r['raw']['min'] * 1e3:.0f}–{r['raw']['max'] * 1e3:.0f}) | "
            f"{rays / raw / 1e6:.1f} | {raw / mk:.2f} | {r['build_s'] * 1e3:.0f} | "
            f"{r['full']['median'] * 1e3:.0f} | {r['mismatched']} |")
    w = results["raytrace"]["whitted"]
    add("")
    add(f"Full Whitted render of `{w['scene']}` at {w['width']}x{w['height']} (max depth "
        f"{w['max_depth']}, reflection and refraction): {_ms(w['times'])} ms "
        f"({w['times']['n']} runs after one warm-up).")
    add("")

    if "groundtruth" in results:
        g = results["groundtruth"]
        add(f"## Ground truth ({g['triangles']:,} triangles, one point light)")
        add("")
        add(f"What each output of docs/CONVENTIONS.md's ground truth adds to a frame of "
            f"`{g['scene']}` at {g['width']}x{g['height']} ({g['objects']} objects, "
            f"{g['casting_objects']} of them casting), in each renderer "
            "(`benchmarks/bench_groundtruth.py`, the variants interleaved round by round): the "
            "rasterizer's `Renderer.render(outputs=...)` with the frame's image, lit and "
            "coverage plus that output, and `raytrace.ground_truth` against "
            "`raytrace.shadow_masks` on one prebuilt Embree backend.  Extra / frame: the "
            "output's cost in frames.  casters counts every candidate caster into its own "
            "counter in one volume pass (image atomics), then turns the counters into the "
            "mask in one pass over the shadow; one read per light.")
        if "run" in g:
            load = " / ".join(f"{x:.2f}" for x in g["run"]["load"])
            add("")
            add(f"This table's own run: commit {g['run']['commit']}, {g['run']['date']}, "
                f"load {load} at its end.")
        add("")
        frame = g["raster"]["frame"]["median"]
        masks = g["raytrace"]["shadow_masks"]["median"]
        add("| outputs | raster (ms) | raster: extra / frame | ray tracer (ms) | "
            "ray tracer / masks |")
        add("|---|---:|---:|---:|---:|")
        for label, r in g["raster"].items():
            rt = g["raytrace"]["shadow_masks" if label == "frame" else label]
            name = "frame (image, lit, coverage); masks" if label == "frame" else label
            add(f"| {name} | {_ms(r)} | {(r['median'] - frame) / frame:+.2f} | "
                f"{_ms(rt)} | {rt['median'] / masks:.2f} |")
        add("")
        for line in bench_groundtruth.target_lines(g):
            add(line)
            add("")

    add("## Memory")
    add("")
    rss = results.get("rss")
    if rss:
        add(f"Peak RSS (VmHWM) of a fresh process that builds the {rss['size']} scene and "
            f"then renders one frame (`Renderer(scene).render()`), against one that computes "
            f"`raytrace.shadow_masks(scene)`:")
        add("")
        add("| process | RSS after building the scene (MB) | peak RSS (MB) | time (s) |")
        add("|---|---:|---:|---:|")
        for what, label in (("frame", "one frame"), ("masks", "the ray tracer's masks")):
            r = rss[what]
            add(f"| {label} | {r['after_scene_mb']:.0f} | {r['peak_mb']:.0f} | "
                f"{r['seconds']:.1f} |")
        add("")
    add("tracemalloc peak = Python-heap allocations (Python objects and numpy arrays) during one "
        "call; it does not see the GL driver's or Embree's own memory.")
    add("")
    add("| what | tracemalloc peak (MB) | ru_maxrss so far (MB) |")
    add("|---|---:|---:|")
    for size, mem in results["memory"].items():
        add(f"| one shadowed frame, {_tri(results, size):,} triangles, auto/cpu | "
            f"{mem['frame_python_peak_mb']:.1f} | {mem['maxrss_mb']:.0f} |")
    for r in results["raytrace"]["masks"]:
        if "memory_python_peak_mb" in r:
            add(f"| `shadow_masks` incl. build, {r['scene']} | "
                f"{r['memory_python_peak_mb']:.1f} | |")
    add("")
    if results.get("extras"):
        add("## The other issues' benchmarks (the same run)")
        add("Each is a script of its own in `benchmarks/`, run by `run.py` after the sections "
            "above, one after another, under the same load; what it printed is kept verbatim.")
        for row in results["extras"]:
            status = ("ok" if row["returncode"] == 0 else
                      f"exit status {row['returncode']}" if row["returncode"] is not None
                      else "timed out")
            add(f"### `{row['command']}`\n\n{row['what']}; {row['seconds']:.0f} s, {status}."
                f"\n\n```\n{row['output']}\n```")
    if history.strip():
        add(history.strip())
        add("")
    md_path.write_text("\n".join(L))


def plot(results: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(13, 5))

    def series(ax, xs, stats, label, **kw):
        med = [s["median"] for s in stats]
        lo = [s["median"] - s["min"] for s in stats]
        hi = [s["max"] - s["median"] for s in stats]
        ax.errorbar(xs, med, yerr=[lo, hi], label=label, marker="o", capsize=3, **kw)

    ax = axes[0]
    rows = results["frames"]
    tri = [r["triangles"] for r in rows]
    for key, label in [("plain", "plain moderngl frame"), ("floor", "ours, no shadows"),
                       ("auto/cpu x1", "ours, shadowed, 1 light"),
                       ("masks/cpu x1", "ours, masks only, 1 light"),
                       ("auto/cpu x4", "ours, shadowed, 4 lights")]:
        if key in rows[0]["times"]:
            series(ax, tri, [r["times"][key] for r in rows], label)
    spot = [p for p in results.get("pyrender", []) if p["light"] == "spot"]
    if spot:
        series(ax, [p["triangles"] for p in spot],
               [p["times"]["pyrender shadowed"] for p in spot], "pyrender shadow map (spot)",
               linestyle="--")
    ax.set(xscale="log", yscale="log", xlabel="triangles", ylabel="frame (ms)",
           title="Frame with read-back vs triangles ({}x{})".format(*results["config"]["size"]))
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)

    ax = axes[1]
    size = HEADLINE_SIZE if any(p["size"] == HEADLINE_SIZE for p in results["phases"]) else \
        results["phases"][-1]["size"]
    rows = [p for p in results["phases"] if p["size"] == size]
    names = [n for n in rows[0]["phases"] if n != "instrumented frame"]
    labels = [f"auto/{p['silhouettes']}" for p in rows]
    bottom = [0.0] * len(rows)
    for name in names:
        vals = [p["phases"][name]["median"] for p in rows]
        ax.bar(labels, vals, bottom=bottom, label=name)
        bottom = [b + v for b, v in zip(bottom, vals)]
    ax.set(ylabel="ms (glFinish-bracketed)", title=f"Phases, {size} triangles, 1 light")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
