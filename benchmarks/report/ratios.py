"""The numbers the tables share: a time's text, a row's medians, the headline ratios and the
floors' bounds."""

from __future__ import annotations

import statistics

HEADLINE_SIZE = "100k"


def spread(s: dict) -> str:
    return f"{s['median']:.1f} ({s['min']:.1f}–{s['max']:.1f})"


def verdict(ok: bool | None) -> str:
    return "—" if ok is None else ("**met**" if ok else "not met")


def find(rows, **key):
    for r in rows:
        if all(r.get(k) == v for k, v in key.items()):
            return r
    return None


def tri_count(results, size) -> int:
    return find(results["frames"], size=size)["triangles"]


def med(row, key) -> float:
    return row["times"][key]["median"]


def further_light(row, n: int, key: str = "auto/cpu") -> float:
    """ms per further light, 1 -> n lights."""
    return (med(row, f"{key} x{n}") - med(row, f"{key} x1")) / (n - 1)


def overflow_cost(o: dict) -> float:
    """The check's cost as a fraction of a frame: the median over rounds of checked /
    unchecked, each pair timed next to each other (the ratio of the medians where a run did not
    record pairs)."""
    if "paired_ratio" in o:
        return o["paired_ratio"]["median"] - 1
    return med(o, "checked") / med(o, "unchecked") - 1


def mitsuba_results(results: dict) -> dict | None:
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
        phase = find(results["phases"], size=row["size"], silhouettes="cpu")
        if phase is None:
            continue
        pl, floor = med(row, "plain"), med(row, "depth floor")
        vol = phase["phases"]["volume pass"]["median"]
        image = med(row, "image floor") if "image floor" in row["times"] else None
        masks = med(row, "mask floor") if "mask floor" in row["times"] else None
        # the lighting arithmetic of the covered pixels, counted only for the share the light
        # lights (an exact frame may skip the others), and never below 0
        per_pixel = (max(med(row, "lighting: lit") - med(row, "lighting: flat"), 0.0)
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
                    "ours": med(row, "auto/cpu x1") / pl})
    return out


def headline(results: dict) -> list[tuple[str, float | None, str, bool | None]]:
    """(what, value, target, met) rows, the issue's targets."""
    out = []
    frames = results["frames"]
    for size in ("100k", "1M", "1k"):
        row = find(frames, size=size)
        if row is None:
            continue
        r = med(row, "auto/cpu x1") / med(row, "plain")
        limit = 2.0 if size == "1k" else 1.5
        out.append((f"{size}, 1 light: shadowed frame (auto, CPU) / plain frame", r,
                    f"≤ {limit:g}", r <= limit))
    for size in ("100k", "1M", "1k"):
        row = find(frames, size=size)
        if row is None or "auto/cpu x4" not in row["times"]:
            continue
        r = further_light(row, 4) / med(row, "plain")
        out.append((f"{size}: each further light (1 → 4) / one plain frame", r, "≤ 0.3",
                    r <= 0.3))
    row = find(frames, size="100k")
    if row is not None:
        r = med(row, "masks/cpu x1") / med(row, "plain")
        out.append(("100k: mask-only frame (lit + coverage) / plain frame", r, "≤ 1.2",
                    r <= 1.2))
    for o in results.get("overflow", []):
        r = overflow_cost(o)
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
            r = med(p, "pyrender shadowed") / med(p, "auto/cpu")
            out.append((f"{p['size']}, 1 {p['light']} light: pyrender shadow-mapped frame / "
                        f"ours (auto, CPU) — speed-up", r, "≥ 15", r >= 15.0))
    return out
