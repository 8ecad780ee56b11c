"""The interactive viewer's frame rate (`shadowvol view`), on every shipped scene.

    python -m benchmarks.bench_viewer [--frames N] [--modes shaded,roles,stencil]

Each frame orbits the camera one step (so the frame is rendered again, as while dragging) and
is timed from the state change to the window's buffer swap: the render in the window's GL
context, the read-back, the side panel, the blit and `flip`.  Without a DISPLAY it starts its
own Xvfb (and stops it).  Prints a markdown table of the median frame time and frames per
second per scene and mode.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _xvfb():
    exe = shutil.which("Xvfb")
    if exe is None:
        sys.exit("no DISPLAY and no Xvfb: apt-get install xvfb")
    n = next(n for n in range(150, 200) if not os.path.exists(f"/tmp/.X11-unix/X{n}"))
    proc = subprocess.Popen([exe, f":{n}", "-screen", "0", "1920x1080x24", "-nolisten", "tcp"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for _ in range(100):
        if os.path.exists(f"/tmp/.X11-unix/X{n}"):
            break
        time.sleep(0.05)
    os.environ["DISPLAY"] = f":{n}"
    return proc


def bench(scene_path: Path, modes, frames: int) -> list[tuple[str, str, float]]:
    from dataclasses import replace

    from shadowvol import load_scene
    from shadowvol.view.app import Viewer
    from shadowvol.view.state import orbit

    scene = load_scene(scene_path)
    viewer = Viewer(scene)
    rows = []
    try:
        for mode in modes:
            viewer.set_state(replace(viewer.state, mode=mode, help=False))
            viewer.draw()
            viewer.window.flip()                      # warm-up: programs, buffers, caps
            times = []
            for _ in range(frames):
                start = time.perf_counter()
                viewer.set_state(orbit(viewer.state, 4.0, 0.0))
                viewer.window.dispatch_events()
                viewer.draw()
                viewer.window.flip()
                times.append(time.perf_counter() - start)
            rows.append((scene_path.stem, mode, statistics.median(times) * 1e3))
    finally:
        viewer.close()
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=20)
    ap.add_argument("--modes", default="shaded,roles,stencil")
    args = ap.parse_args()
    proc = _xvfb() if not os.environ.get("DISPLAY") else None
    try:
        rows = []
        for path in sorted((ROOT / "scenes").glob("*.toml")):
            rows += bench(path, args.modes.split(","), args.frames)
    finally:
        if proc is not None:
            proc.terminate()
            proc.wait(timeout=10)
    print("| scene | mode | frame (ms, median) | frames/s |")
    print("|---|---|---|---|")
    for scene, mode, ms in rows:
        print(f"| {scene} | {mode} | {ms:.0f} | {1e3 / ms:.1f} |")


if __name__ == "__main__":
    main()
