"""Against the peers and the witness: Mitsuba 3, pyrender, the ray tracer, the ground truth."""

from __future__ import annotations

from .. import bench_groundtruth
from .ratios import mask_bound_ms, med, mitsuba_results, spread, verdict


def mitsuba(results: dict) -> list[str]:
    """Mask-only frames against Mitsuba 3's, and the CPU time each costs (`bench_mitsuba`)."""
    L: list[str] = []
    add = L.append
    mitsuba = mitsuba_results(results)
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
            add(f"| {sc['scene']} ({sc['triangles']:,} triangles) | {spread(ours)} | "
                f"{spread(peer)} | {r:.2f} | < 1 | {verdict(r < 1)} |{bound}")
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
                add(f"| {sc['scene']} | {spread(o['during'])} | {spread(o['after'])} | {ot:.1f} | "
                    f"{spread(m['during'])} | {spread(m['after'])} | {mt:.1f} | {ot / mt:.2f} |")
    add("")
    return L


def pyrender(results: dict) -> list[str]:
    """pyrender's shadow-mapped frames of the same scenes."""
    L: list[str] = []
    add = L.append
    if not results.get("pyrender"):
        return []
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
        add(f"| {p['triangles']:,} | {p['light']} | {spread(t_['plain'])} | "
            f"{spread(t_['auto/cpu'])} | {spread(t_['auto/gpu'])} | "
            f"{spread(t_['pyrender unshadowed'])} | {spread(t_['pyrender shadowed'])} | "
            f"{med(p, 'pyrender shadowed') / med(p, 'auto/cpu'):.1f}x | "
            f"{med(p, 'pyrender shadowed') / med(p, 'auto/gpu'):.1f}x |")
    add("")
    return L


def ray_tracer(results: dict) -> list[str]:
    """The ray tracer's masks against raw Embree casts, and a Whitted render."""
    L: list[str] = []
    add = L.append
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
        f"{w['max_depth']}, reflection and refraction): {spread(w['times'])} ms "
        f"({w['times']['n']} runs after one warm-up).")
    add("")
    return L


def ground_truth(results: dict) -> list[str]:
    """What each ground-truth output adds to a frame, in both renderers."""
    L: list[str] = []
    add = L.append
    if "groundtruth" not in results:
        return []
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
        add(f"| {name} | {spread(r)} | {(r['median'] - frame) / frame:+.2f} | "
            f"{spread(rt)} | {rt['median'] / masks:.2f} |")
    add("")
    for line in bench_groundtruth.target_lines(g):
        add(line)
        add("")
    return L
