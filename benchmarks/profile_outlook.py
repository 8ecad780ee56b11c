"""Profile (not a test): where a path-traced frame of the Cornell box spends its time, by stage.

    python -m benchmarks.profile_outlook [--size 512] [--spp 1] [--shading numpy|numba]

One thread (tiles in turn, Embree on the calling thread), so that the stages add up to the frame, in
that thread's CPU time (`time.thread_time`: other processes' load on the cores does not count, as it
does in wall time): each stage is a function of `raytrace.outlook.path.pathtrace` /
`raytrace.outlook.brdf` (the numpy shading) or a kernel of `raytrace.outlook.path.pathkernels` (the
numba shading) timed exclusively (a stage's time leaves out the stages it calls).  "paths: ..." is
what the path loop (`trace_rows`) does itself: with numba, drawing the random numbers (in numpy, as
the numpy path draws them) and the azimuths' cos and sin.  Prints a table and the time of the Embree
casts beside the rest.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CORNELL = ROOT / "scenes" / "cornell.toml"

# (module attribute or PathWorld method, stage name)
STAGES = (
    ("camera_rays", "camera rays"),
    ("PathWorld.closest_rows", "Embree: closest hits"),
    ("PathWorld.occluded_rows", "Embree: shadow rays"),
    ("PathWorld.surface", "hit: surface gather"),
    ("PathWorld.sample_emitters", "NEE: light sampling"),
    ("next_event", "NEE: shading, MIS weight"),
    ("phong_sample_rows", "BSDF: sampling"),
    ("phong_eval_rows", "BSDF: f"),
    ("phong_pdf_rows", "BSDF: pdf"),
    ("_scatter_add", "accumulation into the paths' radiance"),
    ("trace_rows", "paths: hit point, MIS, roulette, compaction"),
    ("render", "tiles: set-up and sums per pixel"),
)
# the same for the numba shading: kernels of raytrace.outlook.path.pathkernels ("k." prefix)
NUMBA_STAGES = (
    ("k.camera_rays", "camera rays (kernel; the jitter drawn in numpy)"),
    ("PathWorld.closest_rows", "Embree: closest hits"),
    ("PathWorld.occluded_rows", "Embree: shadow rays"),
    ("k._hits", "hit: compaction, gather, emission (kernel)"),
    ("k._emitter_rays", "NEE: light sampling, shadow rays (kernel)"),
    ("k._emitter_shade", "NEE: shading, MIS weight (kernel)"),
    ("k._light_rays", "delta lights: shadow rays (kernel)"),
    ("k._light_add", "delta lights: shading (kernel)"),
    ("k._bounce", "BSDF sampling, roulette, compaction (kernel)"),
    ("k._add_direct", "last bounce's accumulation (kernel)"),
    ("k.trace_rows", "paths: random numbers, cos/sin, buffers"),
    ("render", "tiles: set-up and sums per pixel"),
)


def profile(size: int, spp: int, shading: str = "numpy") -> list[tuple[str, float]]:
    from raytrace.outlook.path import pathtrace
    from shadowvol import load_scene

    scene = load_scene(CORNELL).replace(width=size, height=size)
    pathtrace.render(scene.replace(width=16, height=16), spp=1, shading_name=shading)  # warm-up
    stages = STAGES
    if shading == "numba":
        from raytrace.outlook.path import pathkernels
        stages = NUMBA_STAGES
    spent = {name: 0.0 for _, name in stages}
    stack: list[float] = []  # time spent in the children of each open stage

    def timed(fn, name):
        def wrapper(*args, **kwargs):
            stack.append(0.0)
            start = time.thread_time()
            try:
                return fn(*args, **kwargs)
            finally:
                total = time.thread_time() - start
                children = stack.pop()
                spent[name] += total - children
                if stack:
                    stack[-1] += total
        return wrapper

    patched = []
    for target, name in stages:
        owner, attr = (pathtrace.PathWorld, target.split(".")[1]) if \
            target.startswith("PathWorld.") else (pathkernels, target[2:]) if \
            target.startswith("k.") else (pathtrace, target)
        patched.append((owner, attr, getattr(owner, attr)))
        setattr(owner, attr, timed(getattr(owner, attr), name))
    cpu_threads, pathtrace.cpu_threads = pathtrace.cpu_threads, lambda: 1
    init = pathtrace.PathWorld.__init__

    def serial_init(self, *args, **kwargs):  # Embree on the calling thread too
        init(self, *args, **{**kwargs, "parallel": False})

    pathtrace.PathWorld.__init__ = serial_init
    try:
        result = pathtrace.render(scene, spp=spp, seed=0, progress=False,
                                  shading_name=shading)
    finally:
        pathtrace.PathWorld.__init__ = init
        pathtrace.cpu_threads = cpu_threads
        for owner, attr, fn in patched:
            setattr(owner, attr, fn)
    return [(name, spent[name]) for _, name in stages], result


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--spp", type=int, default=1)
    ap.add_argument("--shading", choices=("numpy", "numba"), default="numpy")
    args = ap.parse_args(argv)
    rows, result = profile(args.size, args.spp, args.shading)
    total = sum(t for _, t in rows)
    print(f"{result.rays} rays in {result.seconds:.3f} s wall ({total:.3f} s CPU), one thread, "
          f"{args.shading} shading "
          f"({result.rays / result.seconds / 1e6:.2f} Mrays/s)")
    for name, t in rows:
        print(f"  {name:46s} {1e3 * t:8.1f} ms  {100 * t / total:5.1f} %")
    embree = sum(t for name, t in rows if name.startswith("Embree"))
    print(f"  {'Embree casts / everything else':46s} {1e3 * embree:8.1f} / "
          f"{1e3 * (total - embree):.1f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())
