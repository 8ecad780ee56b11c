"""Profile shadowvol frames of a benchmark scene with cProfile (the Python side; GL work shows up
in the calls that wait for it: reads and glFinish).

    python -m benchmarks.profile_frame --size 100k --lights 1 --method auto --silhouettes cpu

Prints the top functions by cumulative and by own time over --frames frames (after one
warm-up frame).
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys

from . import scenes


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", default="100k", choices=list(scenes.SIZES))
    ap.add_argument("--lights", type=int, default=1)
    ap.add_argument("--method", default="auto")
    ap.add_argument("--silhouettes", default="cpu")
    ap.add_argument("--floor", action="store_true", help="profile the unshadowed frame")
    ap.add_argument("--frames", type=int, default=5)
    ap.add_argument("--top", type=int, default=25)
    args = ap.parse_args(argv)

    from shadowvol import Renderer

    scene = scenes.occluder_scene(args.size, args.lights)
    with Renderer(scene) as r:
        def frame():
            if args.floor:
                r.render(shadows=False)
            else:
                r.render(args.method, args.silhouettes)

        frame()
        prof = cProfile.Profile()
        prof.enable()
        for _ in range(args.frames):
            frame()
        prof.disable()
    st = pstats.Stats(prof).strip_dirs()
    st.sort_stats("cumulative").print_stats(args.top)
    st.sort_stats("tottime").print_stats(args.top)
    return 0


if __name__ == "__main__":
    sys.exit(main())
