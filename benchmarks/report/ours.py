"""Our frames: by size, their floors' bounds, their phases, their Python per object, their
memory."""

from __future__ import annotations

from .ratios import find, further_light, lower_bounds, med, spread, tri_count


def frames(results: dict) -> list[str]:
    """Whole frames by size: their times, and their ratios to the plain frame."""
    L: list[str] = []
    add = L.append
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
        add(f"| {row['triangles']:,} | " + " | ".join(spread(row["times"][k]) for k in keys) +
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
        pl = med(row, "plain")
        x2 = further_light(row, 2) / pl if "auto/cpu x2" in row["times"] else float("nan")
        x4 = further_light(row, 4) / pl if "auto/cpu x4" in row["times"] else float("nan")
        m4 = (further_light(row, 4, "masks/cpu") / pl if "masks/cpu x4" in row["times"]
              else float("nan"))
        add(f"| {row['triangles']:,} | {med(row, 'auto/cpu x1') / pl:.2f} | "
            f"{med(row, 'auto/cpu x1') / med(row, 'floor'):.2f} | "
            f"{med(row, 'floor') / pl:.2f} | {med(row, 'masks/cpu x1') / pl:.2f} | "
            f"{med(row, 'auto/gpu x1') / pl:.2f} | {med(row, 'auto/cpu x1 culled') / pl:.2f} | "
            f"{x2:.2f} | {x4:.2f} | {m4:.2f} |")
    add("")
    return L


def bounds(results: dict) -> list[str]:
    """The least GL work of any exact frame of each size (`numbers.lower_bounds`)."""
    L: list[str] = []
    add = L.append
    bounds = lower_bounds(results)
    if not bounds:
        return []
    add("### What no exact shadow-volume frame can go below here")
    add("")
    add("Any exact shadowed frame rasterises every triangle without back-face culling "
        "(culling is not exact in float32: `methods.cullable`) and counts each light's "
        "volumes in the stencil.  So it costs at least **depth floor + volume pass** "
        "(the volume pass of the phases below: CPU silhouettes, halved and clipped), "
        "before any shading or read-back, and each further light at least one volume "
        "pass, and in a frame that returns the image also that light's lighting where it "
        "lights (**further lighting**: the lighting below per covered pixel, times the "
        "further lights' mean share of the covered pixels they light).  A frame that returns "
        "the masks alone also stores and reads back the bits "
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
    mask = find(bounds, size="100k")
    if mask:
        b = mask["bound"] if mask["mask_bound"] is None else mask["mask_bound"]
        add(f"Mask-only frames at 100k: bound {b:.2f} plain frames, against a target of "
            f"≤ 1.2: {'out of reach' if b > 1.2 else 'not ruled out by the bound'}.")
        add("")
    return L


def phases(results: dict) -> list[str]:
    """A frame's phases, and silhouette extraction alone."""
    L: list[str] = []
    add = L.append
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
        add(f"| {tri_count(results, p['size']):,} | {p['silhouettes']} | " +
            " | ".join(spread(p["phases"][n]) for n in names) + " |")
    add("")
    add("Silhouette extraction alone, all casters, one light: CPU = signs, multiplicities and "
        "side-quad triangles in numpy (no upload; what a moving light pays per frame), GPU = "
        "the edge records through the geometry shader with rasterizer discard "
        "(glFinish-bracketed).")
    add("")
    add("| triangles | CPU (ms) | GPU (ms) | shadowed frame auto/cpu (ms) | faster |")
    add("|---:|---:|---:|---:|---|")
    for size, s in results["silhouettes"].items():
        row = find(results["frames"], size=size)
        add(f"| {tri_count(results, size):,} | {spread(s['cpu'])} | {spread(s['gpu'])} | "
            f"{spread(row['times']['auto/cpu x1'])} | "
            f"{'CPU' if s['cpu']['median'] < s['gpu']['median'] else 'GPU'} |")
    add("")
    return L


def objects(results: dict) -> list[str]:
    """The Python of a frame against the number of objects."""
    L: list[str] = []
    add = L.append
    objects = results.get("objects") or []
    if not objects:
        return []
    add("## Python a frame against the number of objects")
    add("")
    add("Frames of a floor and N small closed casters (`scenes.many_casters_scene`: "
        "icosahedra, 20 triangles each, at 64x48 so the draws are small), one point "
        "light, CPU silhouettes: the whole frame and its wall time outside the GL calls "
        "that can wait for the GL (draws, clears, reads, glFinish: "
        "`frame_timing.python_times`), ms, median (min–max).  The draws are runs of "
        "triangles, not objects; what is left per object is numpy over every object's "
        "box (the z-fail choice, the overflow check's slack).")
    add("")
    add("| objects | triangles | masks: frame | masks: Python | image + masks: frame | "
        "image + masks: Python |")
    add("|---:|---:|---:|---:|---:|---:|")
    for row in objects:
        add(f"| {row['objects']:,} | {row['triangles']:,} | "
            f"{spread(row['masks']['frame'])} | {spread(row['masks']['python'])} | "
            f"{spread(row['image + masks']['frame'])} | "
            f"{spread(row['image + masks']['python'])} |")
    if len(objects) > 1:
        a, b = objects[0], objects[-1]
        per = ((b["masks"]["python"]["median"] - a["masks"]["python"]["median"])
               / (b["objects"] - a["objects"]) * 1e3)
        add("")
        add(f"Python a mask-only frame per further object ({a['objects']:,} → "
            f"{b['objects']:,}): {per:.2f} µs.")
    add("")
    return L


def memory(results: dict) -> list[str]:
    """Peak RSS of a frame against the ray tracer's masks, and the Python heap's peaks."""
    L: list[str] = []
    add = L.append
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
        add(f"| one shadowed frame, {tri_count(results, size):,} triangles, auto/cpu | "
            f"{mem['frame_python_peak_mb']:.1f} | {mem['maxrss_mb']:.0f} |")
    for r in results["raytrace"]["masks"]:
        if "memory_python_peak_mb" in r:
            add(f"| `shadow_masks` incl. build, {r['scene']} | "
                f"{r['memory_python_peak_mb']:.1f} | |")
    add("")
    return L
