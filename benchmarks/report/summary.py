"""The report's head (the run, the machine, the reading guide, the headline ratios) and its
tail (the other benchmark modules' output)."""

from __future__ import annotations

import os
from pathlib import Path

from .ratios import headline, verdict


# the hand-written history beside the generated tables, linked from them
OPTIMISATIONS = Path(__file__).resolve().parents[1] / "OPTIMISATIONS.md"


def header(results: dict, md_path: Path, png_path: Path) -> list[str]:
    """The run's command and machine, the plot and the history (linked relative to the
    markdown), and the reading guide."""
    L: list[str] = []
    add = L.append
    m = results["machine"]
    history = os.path.relpath(OPTIMISATIONS, md_path.parent)
    add("# Benchmarks")
    add("")
    add("Written by `python -m benchmarks.run` from one run's results; do not edit by hand.  "
        f"What each optimisation bought, what was tried and dropped, and where the floor is: "
        f"[{history}]({history}).")
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
    previous = results.get("previous")
    if previous is not None:
        worse = previous["regressions"]
        add(f"- **Against the previous run** (commit {previous['commit']}, "
            "`benchmarks.regressions`): " +
            (f"{len(worse)} {'ratio' if len(worse) == 1 else 'ratios'} worse by more than 15 %: " +
             "; ".join(f"{g['name']} {g['old']:.3g} → {g['new']:.3g}" for g in worse[:8]) +
             (f"; and {len(worse) - 8} more (results.json)" if len(worse) > 8 else "")
             if worse else "no ratio worse by more than 15 %."))
    ls, le = m["load_start"], m["load_end"]
    add(f"- **Load** (1/5/15-min load average; other sessions share the 2 cores): at the start "
        f"{ls[0]:.2f} / {ls[1]:.2f} / {ls[2]:.2f}, at the end {le[0]:.2f} / {le[1]:.2f} / "
        f"{le[2]:.2f}.")
    if results["quick"]:
        add("- **QUICK RUN**: tiny sizes and one or two repeats — a smoke test, not numbers to "
            "quote.")
    add("")
    add("![benchmarks](" + os.path.relpath(png_path, md_path.parent) + ")")
    add("")
    return L + guide()


def guide() -> list[str]:
    """How to read the tables below and how to make them again."""
    return [
        "## Reading these tables",
        "",
        "- **Rerun**: `python -m benchmarks.run` from the checkout's root (the full run, ~15 "
        "min on 2 cores; `--quick` a smoke run on tiny scenes, `--report-only "
        "benchmarks/results.json` this file and the plot again without measuring).  Each "
        "`benchmarks.bench_*` module also runs alone (`python -m benchmarks.bench_soft`).",
        "- **Clocks**: a frame is the wall time of `Renderer.render(...)`, which returns after "
        "reading back what was asked for, so all GL work is inside it; the plain frame "
        "(`benchmarks/plain.py`) returns after its RGBA8 read-back.  Phases are "
        "glFinish-bracketed wall time (llvmpipe renders on flush), from separate instrumented "
        "frames.  Times are milliseconds: median (min–max).",
        "- **Ratios**: the variants a ratio compares are interleaved round by round in the same "
        "minutes, so load slows all of them alike; absolute times are noisier than ratios.  "
        "\"x / plain\" is in plain frames (1.5: half again a plain frame), a speed-up is theirs "
        "/ ours, a per-round ratio the median of each round's own.",
        "- **Against the previous run**: before it replaces results.json, `benchmarks.run` "
        "compares every ratio with the previous run's and prints (and lists at the top) each "
        "one worse by more than 15 %, naming its benchmark and both commits "
        "(`benchmarks/regressions.py`; `python -m benchmarks.regressions NEW OLD` compares two "
        "results.json files).",
        "- **Floors and bounds**: a floor is the least GL work any exact frame of its kind does "
        "on the same triangles (`plain.DepthFloor`, `MaskFloor`, `ImageFloor`); floor + volume "
        "pass bounds every shadow-volume frame, so where a bound exceeds a target no such frame "
        "meets it on this machine, and where it does not, the gap is what is left to win.",
        "- **Sections**: the headline's targets; whole frames by size, their floors and phases; "
        "the overflow check and the turntable on the shared meshes; the Python per object; "
        "the peers (Mitsuba 3, pyrender); the ray tracer against raw Embree; the ground "
        "truth's cost; memory; the other benchmark modules' own output, verbatim, a "
        "page each (docs/benchmarks/ for the full run).",
        "- **Scenes** (`benchmarks/scenes.py`): a 14 x 14 floor and seeded icospheres (closed "
        "meshes) under the same camera; 1, 2 or 4 point lights; the pyrender comparison uses "
        "one spot (45°) or one directional light, since pyrender has no point-light shadows.",
        "",
    ]


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


def extras_folder(png_path: Path) -> Path:
    """Where the other benchmark modules' outputs go: `benchmarks/` beside the plot
    (docs/benchmarks/ for the full run)."""
    return png_path.parent / "benchmarks"


def extra_name(row: dict) -> str:
    """The file of one extra's output: its module's name ("bench_soft.md")."""
    return Path(row["script"]).stem + ".md"


def extra_page(results: dict, row: dict, back: str = "../../BENCHMARKS.md") -> str:
    """One extra's page: its command, what it measures, how long it took and what it
    printed, verbatim, under the run it was part of (`back`: the markdown, relative to the
    page)."""
    m = results["machine"]
    status = ("ok" if row["returncode"] == 0 else
              f"exit status {row['returncode']}" if row["returncode"] is not None
              else "timed out")
    return (f"# `{row['command']}`\n\nWritten by `python -m benchmarks.run` (commit "
            f"{m['commit']}, run {m['date']}) from what the module printed; do not edit by "
            f"hand.  The run's machine, load and the other sections: "
            f"[BENCHMARKS.md]({back}).\n\n{row['what']}; {row['seconds']:.0f} s, "
            f"{status}.\n\n```\n{row['output']}\n```\n")


def extras(results: dict, md_path: Path | None = None, png_path: Path | None = None
           ) -> list[str]:
    """What the other benchmark modules printed in the same run: a line each here, linking
    its page (`extra_page`, written by `write_extras`)."""
    L: list[str] = []
    add = L.append
    if not results.get("extras"):
        return []
    folder = extras_folder(png_path) if png_path is not None else Path("docs/benchmarks")
    where = os.path.relpath(folder, md_path.parent) if md_path is not None else str(folder)
    add("## The other issues' benchmarks (the same run)")
    add("")
    add("Each is a module of its own in `benchmarks/`, run by `run.py` after the sections "
        f"above, one after another, under the same load; what it printed is kept verbatim, "
        f"one page each in [{where}/]({where}/).")
    add("")
    for row in results["extras"]:
        status = ("ok" if row["returncode"] == 0 else
                  f"exit status {row['returncode']}" if row["returncode"] is not None
                  else "timed out")
        add(f"- [`{row['command']}`]({where}/{extra_name(row)}): {row['what']}; "
            f"{row['seconds']:.0f} s, {status}.")
    add("")
    return L


def write_extras(results: dict, md_path: Path, png_path: Path) -> list[Path]:
    """Each extra's page (`extra_page`) in `extras_folder`; the paths written."""
    folder = extras_folder(png_path)
    back = os.path.relpath(md_path, folder)
    written = []
    for row in results.get("extras") or []:
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / extra_name(row)
        path.write_text(extra_page(results, row, back))
        written.append(path)
    return written
