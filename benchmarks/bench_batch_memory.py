"""Benchmark (not a test): does a long `shadowvol batch` with jittered lights keep its memory
flat?  Issue 36 found RSS growing ~10 MB per 1,000 such frames, with no sign of levelling off.

    python -m benchmarks.bench_batch_memory [--frames 10000] [--size 16x12] [--json out.json]
    python -m benchmarks.bench_batch_memory --quick        # a smoke run: 300 frames

One job of the cage scene (scenes/cage.toml), an orbit of N frames with its eye and light
jittered in every frame (so every frame's light is new to every cache keyed by lights), image
and masks, rendered by `shadowvol.batch.run` in this process (one worker) into a temporary
folder.  A thread samples this process's VmRSS a few times a second, with the frames made so
far (the manifest's journal lines); the report gives RSS at the middle and at the end of the
frames (the highest sample in the twentieth of the frames before each), the second half's growth
against the goal (at most 5 MB over 10,000 frames), and the frames/s.  Exit status 0, or with
--check 1 when the goal is not met.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
GOAL_MB = 5.0   # the second half's RSS growth allowed (issue 36, over 10,000 frames)
JITTER = 0.1    # the eye's and the light's jitter radius (scene units; the cage is ~10 wide)


def rss_mb() -> float:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return float("nan")


class Sampler(threading.Thread):
    """(frames made, VmRSS MB) every `every` seconds while a batch writes `journal`: the frames
    are its lines, read as they are appended (never the whole file at once)."""

    def __init__(self, journal: Path, every: float = 0.1):
        super().__init__(daemon=True)
        self.journal, self.every = journal, every
        self.samples: list[tuple[int, float]] = []
        self.stopped = threading.Event()

    def run(self) -> None:
        lines, handle = 0, None
        while not self.stopped.wait(self.every):
            if handle is None and self.journal.exists():
                handle = open(self.journal, "rb")
            if handle is not None:
                while chunk := handle.read(1 << 16):
                    lines += chunk.count(b"\n")
            self.samples.append((lines, rss_mb()))
        if handle is not None:
            handle.close()


def job(frames: int, size: tuple[int, int]) -> dict:
    return {"name": "jittered", "scene": str(ROOT / "scenes" / "cage.toml"), "size": list(size),
            "outputs": ["image", "masks"], "seed": 1, "jitter": {"eye": JITTER, "lights": JITTER},
            "cameras": {"orbit": {"center": [-0.6, 1.0, -0.8], "radius": 7.0,
                                  "elevation": 30.0, "frames": frames}}}


def peak_before(samples: list[tuple[int, float]], frames: int, window: int) -> float:
    """The highest RSS sampled with frames - window up to (not including) frames made: the
    frames' own, never the final manifest's rewrite after the last one."""
    near = [rss for made, rss in samples if frames - window <= made < frames]
    if not near:   # a fast run: none in the window, so the last sample before it
        near = [rss for made, rss in samples if made < frames][-1:]
    return max(near) if near else float("nan")


def measure(frames: int = 10_000, size: tuple[int, int] = (16, 12)) -> dict:
    from shadowvol import batch

    with tempfile.TemporaryDirectory(prefix="bench-batch-memory-") as tmp:
        out = Path(tmp) / "out"
        sampler = Sampler(out / "manifest.jsonl")
        start_rss, began = rss_mb(), time.perf_counter()
        sampler.start()
        try:
            summary = batch.run([job(frames, size)], out, progress=False)
        finally:
            sampler.stopped.set()
            sampler.join()
        seconds = time.perf_counter() - began
    window = max(1, frames // 20)
    middle = peak_before(sampler.samples, frames // 2, window)
    end = peak_before(sampler.samples, frames, window)
    quarter = peak_before(sampler.samples, frames // 4, window)
    return {"frames": frames, "size": list(size), "jitter": JITTER, "made": summary.rendered,
            "status": summary.status, "seconds": round(seconds, 1),
            "frames_per_s": round(summary.rendered / seconds, 1) if seconds else None,
            "rss_mb": {"start": round(start_rss, 1), "quarter": round(quarter, 1),
                       "middle": round(middle, 1), "end": round(end, 1)},
            "second_half_growth_mb": round(end - middle, 2),
            "goal_mb": GOAL_MB, "load": [round(x, 2) for x in os.getloadavg()],
            "samples": len(sampler.samples)}


def report(result: dict) -> str:
    r = result["rss_mb"]
    growth = result["second_half_growth_mb"]
    verdict = "met" if growth <= GOAL_MB else "not met"
    return (f"{result['made']} of {result['frames']} jittered frames at "
            f"{result['size'][0]}x{result['size'][1]} (image + masks, one worker) in "
            f"{result['seconds']} s ({result['frames_per_s']} frames/s), load "
            f"{' / '.join(map(str, result['load']))}\n"
            f"RSS (MB): start {r['start']}, a quarter {r['quarter']}, half {r['middle']}, end "
            f"{r['end']}; second half's growth {growth:+.2f} MB (goal <= {GOAL_MB:g} MB: "
            f"{verdict})")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=10_000)
    ap.add_argument("--size", default="16x12", help="WxH of each frame (default 16x12)")
    ap.add_argument("--quick", action="store_true", help="a smoke run: 300 frames at 8x6")
    ap.add_argument("--json", type=Path, default=None, help="also write the results here")
    ap.add_argument("--check", action="store_true",
                    help="exit status 1 when the second half grows more than the goal")
    args = ap.parse_args(argv)
    width, height = (int(x) for x in args.size.lower().split("x"))
    frames, size = (300, (8, 6)) if args.quick else (args.frames, (width, height))
    if frames < 40:
        ap.error("--frames: at least 40 (each twentieth is a window of the report)")
    result = measure(frames, size)
    print(report(result))
    if args.json is not None:
        args.json.write_text(json.dumps(result, indent=1))
    if result["status"] != 0 or result["made"] != frames:
        print(f"the batch did not make every frame (status {result['status']})",
              file=sys.stderr)
        return 2
    return 1 if args.check and result["second_half_growth_mb"] > GOAL_MB else 0


if __name__ == "__main__":
    sys.exit(main())
