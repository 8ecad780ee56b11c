"""Benchmark (not a test): whole masks with embreex's single rays against Embree's packets,
and the fit of `shadowvol.compare.fastest.SINGLE_RAYS_SLOWER` from them.

    python -m benchmarks.bench_single_masks [--runs 5] [--json FILE]

Each scene (the occluder scenes 10k with 2 point lights, 100k with 1 and 4, 1M with 1, and the
bunny of `bench_masks.bunny_scene` where ../shared/models has it; 1280x720) is made into masks
by `raytrace.shadow_masks`, the Embree scene built each time, as a command makes it, with
$SHADOWVOL_EMBREE set to "packets" and to "single" in turn round by round (the first round
discarded: numba's kernels loaded), the two masks checked byte-equal; medians.  The fit: the
model (`fastest.costs`) charges the single rays SINGLE_RAYS_SLOWER times RAYS_NS_PER_RAY a ray
and the triangles the same either way, so each scene gives 1 + (single - packets) / (the
model's rays at RAYS_NS_PER_RAY), and the constant is the median over the scenes.
"""

from __future__ import annotations

import os
import statistics
import sys
import time

from . import scenes
from .cli import bench_main, load_span
from .bench_masks import BUNNY, bunny_scene

CASES = (("10k", 2), ("100k", 1), ("100k", 4), ("1M", 1))
WIDTH, HEIGHT = 1280, 720


def cases():
    """(name, scene) of every scene measured."""
    out = [(f"occluders-{size}, {lights} lights",
            scenes.occluder_scene(size, lights, WIDTH, HEIGHT)) for size, lights in CASES]
    if scenes.models_dir() is not None and BUNNY.is_file():
        out.append(("bunny", bunny_scene(WIDTH, HEIGHT)))
    return out


def measure(runs: int) -> dict:
    from raytrace import shadow_masks
    from shadowvol.compare.fastest import RAYS_NS_PER_RAY, SHADOW_RAY_SHARE

    before = os.environ.get("SHADOWVOL_EMBREE")
    rows = []
    try:
        for name, scene in cases():
            times, masks = {"packets": [], "single": []}, {}
            for r in range(runs + 1):
                for queries in ("packets", "single"):
                    os.environ["SHADOWVOL_EMBREE"] = queries
                    start = time.perf_counter()
                    lit, coverage = shadow_masks(scene)
                    if r:
                        times[queries].append((time.perf_counter() - start) * 1e3)
                    masks[queries] = lit.tobytes() + coverage.tobytes()
            if masks["packets"] != masks["single"]:
                raise AssertionError(f"{name}: the single rays' masks differ from the packets'")
            packets, single = (statistics.median(times[q]) for q in ("packets", "single"))
            rays = WIDTH * HEIGHT * (1 + SHADOW_RAY_SHARE * len(scene.lights))
            rays_ms = RAYS_NS_PER_RAY * rays / 1e6
            rows.append({"scene": name, "triangles": len(scene.triangles()[1]),
                         "packets_ms": packets, "single_ms": single,
                         "fit": 1 + (single - packets) / rays_ms})
    finally:
        if before is None:
            os.environ.pop("SHADOWVOL_EMBREE", None)
        else:
            os.environ["SHADOWVOL_EMBREE"] = before
    return {"rows": rows, "fit": statistics.median(row["fit"] for row in rows)}


def table(result: dict) -> str:
    lines = ["| scene | triangles | packets ms | single ms | single / packets | fit |",
             "|---|---:|---:|---:|---:|---:|"]
    for row in result["rows"]:
        lines.append(f"| {row['scene']} | {row['triangles']:,} | {row['packets_ms']:.0f} | "
                     f"{row['single_ms']:.0f} | {row['single_ms'] / row['packets_ms']:.2f}x | "
                     f"{row['fit']:.2f} |")
    lines.append(f"\nSINGLE_RAYS_SLOWER fit (median): {result['fit']:.2f}")
    return "\n".join(lines)


def main(argv=None) -> int:
    return bench_main(argv, "bench_single_masks", __doc__, lambda a: measure(a.runs),
                      lambda r, a: f"{a.runs} rounds, {WIDTH}x{HEIGHT}; {load_span(r)}\n"
                                   f"{table(r)}")


if __name__ == "__main__":
    sys.exit(main())
