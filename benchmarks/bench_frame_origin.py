"""What drawing in the eye's float32 frame costs a turntable: the geometry re-expressed at every
eye (soup, per-triangle data, kept side quads rewritten in place; huge triangles looked for),
against a frame fixed at the world's origin (the old world-space upload: nothing rewritten).

One process, one Renderer per variant over the same scene, both warm; the variants alternate
round by round (the order flips every round), each round renders every view of the turntable
once per variant.  Reported: the median (min-max) per-view time of each variant over all rounds,
and the load average.  The fixed frame is `projection.frame_origin` returning the world origin
and `SceneGeometry.set_view` doing nothing (the masks are then world-space float32, as before).

    python -m benchmarks.bench_frame_origin [--views 36] [--rounds 5] [--size 640x480]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

from shadowvol import Renderer
from shadowvol.raster import projection
from shadowvol.raster.platform.context import create_context
from shadowvol.raster.geometry import SceneGeometry

from . import scenes

EYE_FRAME = projection.frame_origin
SET_VIEW = SceneGeometry.set_view


def fixed(on: bool) -> None:
    """Switch to the old fixed world frame (on) or the eye's frame (off)."""
    projection.frame_origin = (lambda camera: np.zeros(3)) if on else EYE_FRAME
    SceneGeometry.set_view = (lambda self, view_proj, near: None) if on else SET_VIEW


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--views", type=int, default=36)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--size", default="640x480")
    args = ap.parse_args()
    if scenes.models_dir() is None:
        sys.exit("the shared meshes are missing (../shared/models)")
    w, h = (int(x) for x in args.size.split("x"))
    scene = scenes.turntable_scene(w, h)
    cameras = scenes.turntable_cameras(args.views)
    ctx = create_context()
    times = {"eye frame": [], "fixed frame": []}
    renderers = {}
    for name in times:
        fixed(name == "fixed frame")
        renderers[name] = Renderer(scene, ctx)
        for cam in cameras[:2]:
            renderers[name].render(camera=cam)   # warm: programs, kept volumes
    for k in range(args.rounds):
        order = list(times) if k % 2 == 0 else list(times)[::-1]
        for name in order:
            fixed(name == "fixed frame")
            r = renderers[name]
            for cam in cameras:
                t0 = time.perf_counter()
                r.render(camera=cam)
                times[name].append(time.perf_counter() - t0)
    fixed(False)
    load = os.getloadavg()
    print(f"turntable: {len(cameras)} views, {w}x{h}, {scenes.triangle_count(scene):,} "
          f"triangles, {len(scene.lights)} lights, {args.rounds} rounds; load average "
          f"{load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    for name, ts in times.items():
        ms = [1e3 * t for t in ts]
        print(f"  {name:12s} median {statistics.median(ms):7.1f} ms/view  "
              f"(min {min(ms):.1f}, max {max(ms):.1f}, n {len(ms)})")
    for r in renderers.values():
        r.release()


if __name__ == "__main__":
    main()
