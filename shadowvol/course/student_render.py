"""`shadowvol course render`: a student's ray-sphere intersection and shadow test driving the
Whitted tracer, beside the tracer's own image, the pixels that differ marked.

The student's image is made in its own process (`render_runner`, with a time limit, as the
grader runs each task); the reference in this one, by the same tracer at the same size.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from raytrace.outlook.whitted import render
from shadowvol.io import encode_srgb
from shadowvol.pictures import legible_rows, tint
from shadowvol.scene import Scene

# Two pixels differ when a channel of their linear colours does by more than this: far above
# the rounding two correct intersections leave (about 1e-15), far below an 8-bit step (1/255).
DIFFERS = 1e-4
DEFAULT_TIMEOUT = 300.0


@dataclass(frozen=True, eq=False)
class RenderPair:
    student: np.ndarray | None   # (H, W, 3) float64 linear, None when the process failed
    reference: np.ndarray        # (H, W, 3) float64 linear
    notes: list[str]             # what the process said (functions left to the tracer, errors)

    @property
    def differ(self) -> np.ndarray:
        """(H, W) bool: the pixels whose colours differ (all of them without a student image)."""
        if self.student is None:
            return np.ones(self.reference.shape[:2], bool)
        return (np.abs(self.student - self.reference) > DIFFERS).any(axis=-1)

    def picture(self) -> np.ndarray:
        ref = encode_srgb(self.reference)
        mine = encode_srgb(self.student) if self.student is not None else np.zeros_like(ref)
        n = int(self.differ.sum())
        return legible_rows([[("your ray_sphere and shadow_ray", mine),
                             ("the reference (raytrace's own)", ref),
                             (f"{n} pixels differ (red)", tint(ref, self.differ))]])


def render_pair(workspace: Path, scene_path: Path, scene: Scene,
                timeout: float = DEFAULT_TIMEOUT) -> RenderPair:
    """Both images of `scene` (loaded from `scene_path`, at the size it has)."""
    reference = render(scene, progress=False)
    with tempfile.TemporaryDirectory(prefix="shadowvol-render-") as tmp:
        out = Path(tmp) / "student.npy"
        job = {"workspace": str(Path(workspace).resolve()),
               "scene": str(Path(scene_path).resolve()), "width": scene.width,
               "height": scene.height, "out": str(out)}
        env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
        try:
            done = subprocess.run([sys.executable, "-m", "shadowvol.course.render_runner"],
                                  input=json.dumps(job), capture_output=True, text=True,
                                  timeout=timeout, cwd=tmp, env=env)
        except subprocess.TimeoutExpired:
            return RenderPair(None, reference, [f"the render ran past its time limit of "
                                                f"{timeout:g} s (an endless loop?)"])
        notes = [line for line in done.stdout.splitlines() if line.startswith("note: ")]
        if done.returncode != 0 or not out.is_file():
            last = (done.stderr.strip().splitlines() or ["no message"])[-1]
            return RenderPair(None, reference, notes + [
                f"the render process died (exit status {done.returncode}): {last}"])
        return RenderPair(np.load(out), reference, notes)
