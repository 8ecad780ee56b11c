"""The shared meshes: the stencil-overflow check's cost and the turntable."""

from __future__ import annotations

from .ratios import med, overflow_cost, spread


def overflow(results: dict) -> list[str]:
    """The stencil-overflow check's cost on the shared meshes."""
    L: list[str] = []
    add = L.append
    if not results.get("overflow"):
        return []
    add("## The stencil-overflow check on real meshes")
    add("")
    add("Each shared mesh on a floor, one point light, the same renderer with "
        "`check_overflow` on and off, interleaved (25 rounds, every other one in reverse "
        "order, so checked and unchecked always run next to each other).  The cost of the "
        "check is the median over the rounds of checked / unchecked − 1 (min–max over the "
        "rounds beside it); the ratio of the two medians is shown too.  The re-check (one "
        "saturating volume "
        "pass per light and a stencil read) runs when the scene's bound reaches 256 and, "
        "from a light's second frame on, only when that light's bound "
        "(`overflow.detect.light_bound`) does too.")
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
            f"{spread(o['times']['plain'])} | "
            f"{spread(o['times']['checked'])} | {spread(o['times']['unchecked'])} | "
            f"{(med(o, 'checked') / med(o, 'unchecked') - 1) * 100:+.0f}% | "
            f"{overflow_cost(o) * 100:+.0f}%" +
            (f" ({(o['paired_ratio']['min'] - 1) * 100:+.0f}% to "
             f"{(o['paired_ratio']['max'] - 1) * 100:+.0f}%)" if "paired_ratio" in o
             else "") + " |")
    add("")
    return L


def turntable(results: dict) -> list[str]:
    """The turntable of the shared meshes: ours against the ray tracer's masks per view."""
    L: list[str] = []
    add = L.append
    t = results.get("turntable") or {}
    if not t:
        return []
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
    add(f"| ours, masks + image | {spread(t['ours'])} | {t['ours_total_s']:.2f} |")
    add(f"| ours, masks only | {spread(t['ours_masks'])} | |")
    add(f"| raytrace.shadow_masks | {spread(t['raytrace'])} | {t['raytrace_total_s']:.2f} |")
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
        add("| " + " | ".join(spread(ph[n]) for n in names) + " |")
        add("")
        need = t["raytrace"]["median"] / 3.0
        vol = ph["volume pass"]["median"]
        add(f"A 3x speed-up needs a view in {need:.1f} ms; the volume passes alone take "
            f"{vol:.1f} ms and the geometry pass {ph['geometry pass']['median']:.1f} ms "
            f"(the meshes are open or have holes, so their side quads cannot be halved "
            f"and each silhouette loop's quads fill the screen down to the floor).")
        add("")
    return L
