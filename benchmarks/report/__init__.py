"""BENCHMARKS.md and its plot, written from one run's results (`benchmarks.run`).

Each section of the markdown is one function returning its lines (`summary`, `ours`,
`meshes`, `peers`); the numbers they share are `ratios`.  The other benchmark modules' outputs
are pages of their own beside the plot (`summary.write_extras`: docs/benchmarks/ for the full
run), each linked from the markdown.
"""

from __future__ import annotations

from pathlib import Path

from . import meshes, ours, peers, summary
from .plot import plot

# the sections after the headline, in the order the markdown gives them
SECTIONS = (peers.mitsuba, ours.frames, ours.bounds, ours.phases, meshes.overflow,
            ours.objects, meshes.turntable, peers.pyrender, peers.ray_tracer,
            peers.ground_truth, ours.memory)


def write(results: dict, md_path: Path, png_path: Path) -> None:
    """BENCHMARKS.md at `md_path` and the plot at `png_path`, from a run's `results`."""
    plot(results, png_path)
    lines = summary.header(results, md_path, png_path) + summary.headline_table(results)
    for section in SECTIONS:
        lines += section(results)
    lines += summary.extras(results, md_path, png_path)
    summary.write_extras(results, md_path, png_path)
    text = "\n".join(lines)
    md_path.write_text(text if text.endswith("\n") else text + "\n")
