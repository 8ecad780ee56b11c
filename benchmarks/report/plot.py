"""The plot beside BENCHMARKS.md: frame time against triangles, and a frame's phases."""

from __future__ import annotations

from pathlib import Path

from .ratios import HEADLINE_SIZE


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
