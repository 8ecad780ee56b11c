"""The sections of a run measured in processes of their own: the peak RSS of a frame against the
ray tracer's masks, and the other benchmark modules (EXTRAS)."""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from .machine import log

ROOT = Path(__file__).resolve().parents[1]

# VmHWM, the peak RSS of this process's memory since exec (ru_maxrss would carry the parent's
# peak over from fork)
RSS_CHILD = """
import time
def hwm_mb():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
from benchmarks import scenes
scene = scenes.occluder_scene({size!r}, 1, 1280, 720)
base = hwm_mb()
t0 = time.perf_counter()
if {what!r} == "frame":
    from shadowvol import Renderer
    with Renderer(scene) as r:
        r.render()
else:
    from raytrace import shadow_masks
    shadow_masks(scene)
print(base, hwm_mb(), time.perf_counter() - t0)
"""


def rss_section(cfg) -> dict:
    """Peak RSS of one process that builds the scene and renders one frame, against one that
    computes the ray tracer's masks of it (each in a fresh process: the peak is monotone)."""
    out = {"size": cfg["rss_size"]}
    for what in ("frame", "masks"):
        code = RSS_CHILD.format(size=cfg["rss_size"], what=what)
        done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                              text=True, check=True)
        scene_mb, peak_mb, seconds = (float(x) for x in done.stdout.split()[-3:])
        out[what] = {"after_scene_mb": scene_mb, "peak_mb": peak_mb, "seconds": seconds}
    log(f"rss {cfg['rss_size']}: frame {out['frame']['peak_mb']:.0f} MB, masks "
        f"{out['masks']['peak_mb']:.0f} MB")
    return out


# The other issues' benchmarks, each a module of its own (benchmarks/bench_*.py), run by this
# command in the same run and reported verbatim: (name, arguments, what it measures).  The
# ground truth's (bench_groundtruth.py) is measured in the run itself: its own section.
EXTRAS = (
    ("bench_mitsuba.py", ["--json", "{json}"],
     "mask-only frames against Mitsuba 3's llvm_ad_rgb masks (an optional peer: the bench "
     "extra) and raytrace.shadow_masks, bunny, 100k and 1M (issue: frame cost)"),
    ("bench_soft.py", ["--size", "100k"],
     "soft shadows: a rect light of N = 1, 4, 16, 64 samples against point lights, and the "
     "raster against the ray tracer's lit_count (issue: soft shadows)"),
    ("bench_batch.py", [],
     "shadowvol batch on the 36-view turntable of the shared meshes: 1 worker, 2 workers, 2 "
     "shards, Ray with 2 actors, and the machinery's overhead (issue: datasets at scale)"),
    ("bench_batch_memory.py", ["--json", "{json}"],
     "RSS through a 10,000-frame batch with a jittered eye and light (the cage at 16x12, "
     "image + masks): the second half's growth, goal <= 5 MB (issue: as shipped, nothing "
     "lost)"),
    ("bench_soba.py", ["--json", "{json}"],
     "36,000 exact instance-shadow pairs (--format soba-lights) from the shared meshes at random "
     "poses, with the batch's eye and light jitter: pairs/s and peak RSS on one worker "
     "(issue: shadow truth for learning)"),
    ("bench_outlook.py", ["--json", "{json}"],
     "path tracing Mrays/s against raw Embree casts, radiosity at ~1k/4k/16k patches (issue: "
     "the lecture's outlook)"),
    ("bench_time_to_rmse.py", ["--json", "{json}"],
     "the path tracer's CPU time to a fixed RMSE on the Cornell box against Mitsuba 3's path "
     "integrator (an optional peer: the bench extra) in the same run (issue: the path tracer "
     "as efficient as the best)"),
    ("bench_turntable_masks.py", ["--views", "36", "--rounds", "2"],
     "raytrace.shadow_masks per view of the 36-view turntable of the shared meshes (point, "
     "directional and spot light), this checkout alone (`--against` older checkouts for the "
     "before/after; issue: rays at full speed)"),
    ("bench_open3d.py", ["--json", "{json}"],
     "raytrace.shadow_masks against the naive masks of Open3D's RaycastingScene (an optional "
     "peer: the bench extra), bunny and turntable (issue: rays at full speed)"),
    ("bench_peers.py", ["--json", "{json}"],
     "exact masks, the ray tracer's and the raster mask-only frame's, against Open3D's "
     "RaycastingScene and Mitsuba 3 llvm_ad_rgb (optional peers: the bench extra) on 100k, 1M, "
     "two bunnies and 4 turntable views; the ground truth against the masks, ns per ray, "
     "1 -> 2 threads (issue: rays at full speed)"),
    ("bench_packets.py", ["--json", "{json}"],
     "ns a ray of Embree's packets (rtcIntersect16/rtcOccluded16 driven by numba) against "
     "embreex's single rays, the same rays and answers, 1 and 2 threads (issue: rays at full "
     "speed)"),
    ("bench_fastest.py", ["--json", "{json}"],
     "`shadowvol masks --renderer auto` against the renderer it did not choose, scenes of 1k to "
     "1M triangles and 1 to 144 hard lights, and the cost model fitted again (issue: rays at "
     "full speed)"),
    ("bench_exact_soft.py", [],
     "exact soft shadows (raytrace.exact_soft) against counting 64, 256 and 1,024 samples on "
     "scenes/soft.toml, a closed non-convex mesh of 5,120 triangles and the bunny under a rect "
     "light, ms per frame (issue 41)"),
    ("bench_mitsuba_soft.py", ["--json", "{json}"],
     "Mitsuba 3's direct integrator under a rectangle emitter (scalar_rgb; an optional peer: "
     "the bench extra) against the exact irradiance on scenes/soft.toml: a t-test of the "
     "penumbra's mean (issue 41)"),
    ("bench_viewer.py", ["--frames", "15"],
     "the viewer's frame rate on the shipped scenes, under its own Xvfb (issue: the course)"),
)
EXTRA_TIMEOUT_S = 900


def _module(script: str) -> str:
    """The module an EXTRAS script runs as: "bench_soft.py" -> "benchmarks.bench_soft"."""
    return "benchmarks." + script.removesuffix(".py")


def extras_section() -> list[dict]:
    """Run every EXTRAS script once, in this run, one after another; keep what it prints."""
    rows = []
    for script, listed, what in EXTRAS:
        # "{json}": a file the script writes its results to, kept in results.json
        json_path = Path(tempfile.mkstemp(suffix=".json")[1]) if "{json}" in listed else None
        args = [str(json_path) if a == "{json}" else a for a in listed]
        command = [sys.executable, "-m", _module(script), *args]
        log(f"extra: {script} {' '.join(args)}")
        start = time.perf_counter()
        try:
            done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True,
                                  timeout=EXTRA_TIMEOUT_S)
            output, rc = done.stdout + (done.stderr[-2000:] if done.returncode else ""), \
                done.returncode
        except subprocess.TimeoutExpired as exc:
            output, rc = f"timed out after {exc.timeout} s", None
        data = None
        if json_path is not None:
            try:
                data = json.loads(json_path.read_text() or "null")
            except (OSError, ValueError):
                data = None
            json_path.unlink(missing_ok=True)
        shown = [a for a in listed if a not in ("--json", "{json}")]
        rows.append({"script": script, "command": " ".join(["python -m", _module(script), *shown]),
                     "what": what, "seconds": time.perf_counter() - start,
                     "returncode": rc, "output": output.strip(), "results": data})
    return rows
