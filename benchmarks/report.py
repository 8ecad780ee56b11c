"""BENCHMARKS.md and its plot, written from one run's results (see `run`)."""

from __future__ import annotations

import os
from pathlib import Path

HEADLINE_SIZE = "100k"
# "well under one frame": our reading of the silhouette target
SILHOUETTE_FRACTION = 0.25


def _ms(s: dict) -> str:
    return f"{s['median']:.1f} ({s['min']:.1f}–{s['max']:.1f})"


def _met(ok: bool | None) -> str:
    return "—" if ok is None else ("**met**" if ok else "not met")


def _find(rows, **key):
    for r in rows:
        if all(r.get(k) == v for k, v in key.items()):
            return r
    return None


def headline(results: dict) -> list[tuple[str, float | None, str, bool | None]]:
    """(what, value, target, met) rows."""
    out = []
    size = HEADLINE_SIZE if _find(results["frames"], size=HEADLINE_SIZE) else \
        results["frames"][-1]["size"]
    one = _find(results["frames"], size=size, lights=1)
    floor1 = one["times"]["floor"]["median"]
    for sil in ("cpu", "gpu"):
        r = one["times"][f"auto/{sil}"]["median"] / floor1
        out.append((f"{size}, 1 light: shadowed frame (auto, {sil.upper()} silhouettes) / floor",
                    r, "≤ 2", r <= 2.0))
    for p in results["pyrender"]:
        if p["size"] == size:
            for sil in ("cpu", "gpu"):
                r = p["times"]["pyrender shadowed"]["median"] / p["times"][f"auto/{sil}"]["median"]
                out.append((f"{size}, 1 {p['light']} light: pyrender shadow-mapped frame / ours "
                            f"(auto, {sil.upper()}) — speed-up", r, "≥ 8", r >= 8.0))
    for n in (2, 4):
        row = _find(results["frames"], size=size, lights=n)
        if row is None:
            continue
        for sil in ("cpu", "gpu"):
            extra = (row["times"][f"auto/{sil}"]["median"]
                     - one["times"][f"auto/{sil}"]["median"]) / (n - 1)
            out.append((f"{size}: each further light (1 → {n}, auto, {sil.upper()}) / one floor",
                        extra / floor1, "≤ 1", extra / floor1 <= 1.0))
    for m in results["raytrace"]["masks"]:
        r = m["raw"]["median"] / m["masks"]["median"]
        out.append((f"{m['scene']}: masks / raw Embree throughput", r, "≥ 0.8", r >= 0.8))
    big = max(results["silhouettes"], key=lambda k: _tri(results, k))
    frame_big = _find(results["frames"], size=big, lights=1)["times"]["auto/cpu"]["median"]
    for sil in ("cpu", "gpu"):
        r = results["silhouettes"][big][sil]["median"] / frame_big
        out.append((f"{big}: {sil.upper()} silhouette extraction / one shadowed frame", r,
                    f"well under 1 (≤ {SILHOUETTE_FRACTION})", r <= SILHOUETTE_FRACTION))
    return out


def _tri(results, size) -> int:
    return _find(results["frames"], size=size)["triangles"]


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
        "reading back the image (RGBA32F) and each light's lit mask (R8), so all GL work is "
        "inside it.  Phases are glFinish-bracketed wall time (llvmpipe renders on flush), from "
        "separate instrumented frames.  Times are milliseconds: median (min–max).")
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

    add("## Frames at {}x{}".format(*results["config"]["size"]))
    add("")
    variants = [k for k in results["frames"][0]["times"] if k != "floor"]
    add("Whole frame with read-back, ms.  Per size one renderer of the 4-light scene renders "
        "its first 1, 2 or 4 lights, all rows of a size interleaved in the same rounds.  "
        "`auto` z-fails only the casters the near-clip test flags (the last column counts "
        "them); setup = scene upload + topology, once.")
    add("")
    add("| triangles | lights | floor | " + " | ".join(variants) +
        " | auto z-fail casters | setup (s) |")
    add("|---:|---:|" + "---:|" * (len(variants) + 3))
    for r in results["frames"]:
        add(f"| {r['triangles']:,} | {r['lights']} | {_ms(r['times']['floor'])} | " +
            " | ".join(_ms(r["times"][v]) for v in variants) +
            f" | {r['auto_zfail_casters']}/{r['casters'] * r['lights']} | {r['setup_s']:.1f} |")
    add("")
    add("Shadowed / floor (medians):")
    add("")
    add("| triangles | lights | " + " | ".join(variants) + " |")
    add("|---:|---:|" + "---:|" * len(variants))
    for r in results["frames"]:
        f = r["times"]["floor"]["median"]
        add(f"| {r['triangles']:,} | {r['lights']} | " +
            " | ".join(f"{r['times'][v]['median'] / f:.2f}" for v in variants) + " |")
    add("")

    add("## Phases (one light)")
    add("")
    add("glFinish-bracketed wall time per phase, ms, median (min–max) of instrumented frames. "
        "With GPU silhouettes the silhouettes run inside the volume pass (geometry shader).")
    add("")
    names = ["depth+ambient", "silhouettes (CPU, incl. upload)", "volume pass", "lighting pass",
             "read-back", "instrumented frame"]
    add("| triangles | method | silhouettes | " + " | ".join(names) + " |")
    add("|---:|---|---|" + "---:|" * len(names))
    for p in results["phases"]:
        add(f"| {_tri(results, p['size']):,} | {p['method']} | {p['silhouettes']} | " +
            " | ".join(_ms(p["phases"][n]) for n in names) + " |")
    add("")
    add("Silhouette extraction alone, all casters, one light: CPU = signs, multiplicities and "
        "side-quad triangles in numpy (no upload); GPU = the edge records through the geometry "
        "shader with rasterizer discard (glFinish-bracketed).")
    add("")
    add("| triangles | CPU (ms) | GPU (ms) | shadowed frame auto/cpu (ms) |")
    add("|---:|---:|---:|---:|")
    for size, s in results["silhouettes"].items():
        frame = _find(results["frames"], size=size, lights=1)["times"]["auto/cpu"]
        add(f"| {_tri(results, size):,} | {_ms(s['cpu'])} | {_ms(s['gpu'])} | {_ms(frame)} |")
    add("")

    add(f"## Resolution scaling ({results['config']['resolution_size']} triangles, one light)")
    add("")
    rv = [k for k in results["resolution"][0]["times"]]
    add("| size | pixels | " + " | ".join(rv) + " | auto/cpu / floor |")
    add("|---|---:|" + "---:|" * (len(rv) + 1))
    for r in results["resolution"]:
        t = r["times"]
        add(f"| {r['width']}x{r['height']} | {r['width'] * r['height']:,} | " +
            " | ".join(_ms(t[k]) for k in rv) +
            f" | {t['auto/cpu']['median'] / t['floor']['median']:.2f} |")
    add("")

    add("## pyrender 0.1.45, the same scenes")
    add("")
    if results["pyrender"]:
        add("pyrender's `OffscreenRenderer.render` (4x multisampled; reads colour and depth "
            "back) with `SHADOWS_SPOT | SHADOWS_DIRECTIONAL` or without, on its own EGL "
            "context, interleaved with ours.  Speed-up = pyrender shadowed / ours.")
        add("")
        add("| triangles | light | our floor | ours auto/cpu | ours auto/gpu | "
            "pyrender unshadowed | pyrender shadowed | speed-up (cpu) | speed-up (gpu) |")
        add("|---:|---|---:|---:|---:|---:|---:|---:|---:|")
        for p in results["pyrender"]:
            t = p["times"]
            ps = t["pyrender shadowed"]["median"]
            add(f"| {p['triangles']:,} | {p['light']} | {_ms(t['floor'])} | "
                f"{_ms(t['auto/cpu'])} | {_ms(t['auto/gpu'])} | "
                f"{_ms(t['pyrender unshadowed'])} | {_ms(t['pyrender shadowed'])} | "
                f"{ps / t['auto/cpu']['median']:.1f}x | {ps / t['auto/gpu']['median']:.1f}x |")
    else:
        add("Skipped (--no-pyrender).")
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
            "output's cost in frames.  casters counts each candidate caster's volumes alone "
            "(one volume pass and one stencil read of the shadow's box each).")
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

    add("## Memory")
    add("")
    add("tracemalloc peak = Python-heap allocations (Python objects and numpy arrays) during one "
        "call; it does not see the GL driver's or Embree's own memory.  ru_maxrss = the whole "
        "process's peak resident set (Python, numpy, llvmpipe's buffers and threads, Embree), "
        "monotone over the run, read after each section.")
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
    add(f"| after the frame sections | | {results['maxrss_after_frames_mb']:.0f} |")
    add(f"| after pyrender | | {results['maxrss_after_pyrender_mb']:.0f} |")
    add(f"| end of the run | | {results['maxrss_end_mb']:.0f} |")
    add("")
    if history.strip():
        add(history.strip())
        add("")
    md_path.write_text("\n".join(L))


def plot(results: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(13, 9.5))

    def series(ax, xs, stats, label, **kw):
        med = [s["median"] for s in stats]
        lo = [s["median"] - s["min"] for s in stats]
        hi = [s["max"] - s["median"] for s in stats]
        ax.errorbar(xs, med, yerr=[lo, hi], label=label, marker="o", capsize=3, **kw)

    # (a) frame time vs triangles, one light
    ax = axes[0, 0]
    one = [r for r in results["frames"] if r["lights"] == 1]
    tri = [r["triangles"] for r in one]
    for key, label in [("floor", "floor (no shadows)"), ("auto/cpu", "auto, CPU silhouettes"),
                       ("auto/gpu", "auto, GPU silhouettes"), ("zfail/cpu", "z-fail, CPU")]:
        series(ax, tri, [r["times"][key] for r in one], label)
    spot = [p for p in results["pyrender"] if p["light"] == "spot"]
    if spot:
        series(ax, [p["triangles"] for p in spot],
               [p["times"]["pyrender shadowed"] for p in spot], "pyrender shadow map (spot)",
               linestyle="--")
    ax.set(xscale="log", yscale="log", xlabel="triangles", ylabel="frame (ms)",
           title="Frame with read-back vs triangles (1 light, {}x{})".format(
               *results["config"]["size"]))
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)

    # (b) frame time vs lights
    ax = axes[0, 1]
    for size in results["silhouettes"]:
        rows = [r for r in results["frames"] if r["size"] == size]
        n = [r["lights"] for r in rows]
        series(ax, n, [r["times"]["auto/cpu"] for r in rows], f"{size} auto/cpu")
        series(ax, n, [r["times"]["floor"] for r in rows], f"{size} floor", linestyle=":")
    ax.set(yscale="log", xlabel="lights", ylabel="frame (ms)", title="Frame vs lights",
           xticks=sorted({r["lights"] for r in results["frames"]}))
    ax.legend(fontsize=7, ncol=2)
    ax.grid(True, which="both", alpha=0.3)

    # (c) resolution
    ax = axes[1, 0]
    res = results["resolution"]
    px = [r["width"] * r["height"] / 1e6 for r in res]
    for key in ("floor", "auto/cpu", "auto/gpu", "zfail/cpu"):
        series(ax, px, [r["times"][key] for r in res], key)
    ax.set(xlabel="megapixels", ylabel="frame (ms)",
           title=f"Resolution scaling ({results['config']['resolution_size']} triangles, 1 light)")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)

    # (d) phases at the headline size
    ax = axes[1, 1]
    size = HEADLINE_SIZE if any(p["size"] == HEADLINE_SIZE for p in results["phases"]) else \
        results["phases"][-1]["size"]
    rows = [p for p in results["phases"] if p["size"] == size]
    names = ["depth+ambient", "silhouettes (CPU, incl. upload)", "volume pass",
             "lighting pass", "read-back"]
    labels = [f"{p['method']}/{p['silhouettes']}" for p in rows]
    bottom = [0.0] * len(rows)
    for name in names:
        vals = [p["phases"][name]["median"] for p in rows]
        ax.bar(labels, vals, bottom=bottom, label=name)
        bottom = [b + v for b, v in zip(bottom, vals)]
    ax.set(ylabel="ms (glFinish-bracketed)", title=f"Phases, {size} triangles, 1 light")
    ax.legend(fontsize=8)
    ax.tick_params(axis="x", labelrotation=30)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
