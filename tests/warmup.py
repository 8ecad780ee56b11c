"""numba's disk cache made once, before pytest-xdist's workers start (tests/conftest.py,
`pytest_xdist_setupnodes`).

On a clean checkout every numba kernel is compiled in each worker that calls it: the same
machine code two or four times over (on 2 cores the raytrace tests alone took 164 s cold
against 98 s warm; CI's whole suite 627 s on a fresh clone, 520 and 578 s with this, its
~75 s included).  Where the suite runs on several workers and the checkout's kernels have
no cache yet, two processes first run small frames that call them, each its own half (the
block path of the exact visibility of area lights; its other paths, the masks, counts,
ground truth and path tracer), side by side; the workers then load what they wrote.  A kernel neither calls is compiled where a test calls it, as before, and a
warm-up that fails or runs past `LIMIT` seconds only leaves that work to the workers: no
test depends on it.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LIMIT = 600


def blocks() -> None:
    """The block path of `exact_visibility` (a non-convex mesh over a floor): ~70 s of
    compiling on one core, the most of any half."""
    from benchmarks.bench_exact_soft import blob_scene
    from raytrace.exact_soft import exact_visibility

    exact_visibility(blob_scene(24))


def rays() -> None:
    """The pixel path and the convex bodies' path of `exact_visibility`, the counted samples,
    the masks, the ground truth and the path tracer's numba shading (~45 s)."""
    from benchmarks.bench_exact_soft import _soft
    from raytrace.exact_soft import exact_visibility
    from raytrace.groundtruth import ground_truth
    from raytrace.masks import shadow_masks
    from raytrace.outlook.path.pathtrace import render
    from raytrace.soft import lit_counts
    from shadowvol.scenefile import load_scene

    exact_visibility(_soft(32))
    lit_counts(_soft(32))
    scene = load_scene(ROOT / "scenes" / "cage.toml").replace(width=32, height=24)
    shadow_masks(scene)
    ground_truth(scene)
    os.environ["SHADOWVOL_PATHTRACE"] = "numba"
    render(load_scene(ROOT / "scenes" / "cornell.toml").replace(width=16, height=16), spp=1)


def cold() -> bool:
    """Whether the checkout's kernels have no disk cache yet (numba's index files)."""
    return not any((ROOT / "raytrace" / "__pycache__").glob("*kernels*.nbi"))


def warm() -> None:
    """`blocks` and `rays` in two processes side by side, waited for (at most LIMIT seconds);
    their output and failures are dropped."""
    path = [str(ROOT), str(ROOT / "tests"), os.environ.get("PYTHONPATH", "")]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, path)))
    runs = [subprocess.Popen([sys.executable, "-c", f"import warmup; warmup.{name}()"],
                             cwd=ROOT, env=env, stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL) for name in ("blocks", "rays")]
    end = time.monotonic() + LIMIT
    for run in runs:
        try:
            run.wait(timeout=max(0.0, end - time.monotonic()))
        except subprocess.TimeoutExpired:
            run.kill()
            run.wait()
