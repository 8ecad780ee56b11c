"""The report's head (the run, the machine, the headline ratios) and its tail (the other
benchmark modules' output, the optimisation history)."""

from __future__ import annotations

import os
from pathlib import Path

from .ratios import headline, verdict


def header(results: dict, md_path: Path, png_path: Path) -> list[str]:
    """The run's command, machine, clocks and scenes, and the plot (linked relative to the
    markdown)."""
    L: list[str] = []
    add = L.append
    m = results["machine"]
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
    return L


def headline_table(results: dict) -> list[str]:
    """Every headline ratio against its target."""
    L: list[str] = []
    add = L.append
    add("## Headline ratios and targets")
    add("")
    add("| ratio | value | target | |")
    add("|---|---:|---|---|")
    for what, value, target, ok in headline(results):
        add(f"| {what} | {value:.2f} | {target} | {verdict(ok)} |")
    add("")
    return L


def extras(results: dict) -> list[str]:
    """What the other benchmark modules printed in the same run."""
    L: list[str] = []
    add = L.append
    if not results.get("extras"):
        return []
    add("## The other issues' benchmarks (the same run)")
    add("Each is a script of its own in `benchmarks/`, run by `run.py` after the sections "
        "above, one after another, under the same load; what it printed is kept verbatim.")
    for row in results["extras"]:
        status = ("ok" if row["returncode"] == 0 else
                  f"exit status {row['returncode']}" if row["returncode"] is not None
                  else "timed out")
        add(f"### `{row['command']}`\n\n{row['what']}; {row['seconds']:.0f} s, {status}."
            f"\n\n```\n{row['output']}\n```")
    return L


def history_lines(history: str) -> list[str]:
    """The optimisation history, verbatim."""
    L: list[str] = []
    add = L.append
    if not history.strip():
        return []
    add(history.strip())
    add("")
    return L
