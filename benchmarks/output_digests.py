"""Every output file of a set of commands of both tools, by sha256: the check that a refactor
changed no byte of what the product writes.

    python -m benchmarks.output_digests /tmp/before            (on the commit before)
    python -m benchmarks.output_digests /tmp/after --against /tmp/before/digests.json

Runs, at small sizes (a few seconds each), `shadowvol render` of scenes/cage.toml (every file:
masks with all the ground truth, EXR, 16-bit PNG) and scenes/soft.toml (masks, all ground
truth), `raytrace masks --outputs all` of both, `raytrace render` (Whitted at depth 2, the path
tracer at 4 spp, the photon map), `raytrace tree`, `raytrace radiosity` (and its flat display)
and `shadowvol batch --format files` of a rasterized and a ray-traced job; each as a process of
its own, from this checkout.  OUT/digests.json maps every file written (the batch's manifest
aside: it records times and versions) to its sha256; with --against, a file missing, added or
different is named and the exit status is 1.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SIZE = (96, 72)          # the scenes' images
CARDS = ("cage", "soft", "cornell")

JOBS = [
    {"name": "cage-turntable", "scene": str(ROOT / "scenes/cage.toml"), "size": [80, 60],
     "cameras": {"orbit": {"center": [-0.6, 1.0, -0.8], "radius": 7.5, "elevation": 28.0,
                           "start": 10.0, "sweep": 80.0, "frames": 3}},
     "outputs": ["image", "masks", "depth", "normal", "object_id", "facing", "casters"],
     "renderer": "shadowvol", "seed": 0},
    {"name": "soft-rays", "scene": str(ROOT / "scenes/soft.toml"), "size": [48, 36],
     "cameras": {"orbit": {"center": [0.0, 0.5, 0.0], "radius": 6.0, "elevation": 30.0,
                           "start": 0.0, "sweep": 40.0, "frames": 2}},
     "outputs": ["image", "masks", "depth", "distance", "facing_count", "casters"],
     "renderer": "raytrace", "seed": 1},
]


def commands(s: Path, r: Path) -> list[list[str]]:
    """(tool, args...) of every command: scenes from `s`, files into `r`."""
    return [
        ["shadowvol", "render", f"{s}/cage.toml", "-o", f"{r}/cage.png", "--masks",
         f"{r}/cage.npz", "--outputs", "all", "--exr", f"{r}/cage.exr", "--png16",
         f"{r}/cage16.png"],
        ["shadowvol", "render", f"{s}/soft.toml", "-o", f"{r}/soft.png", "--masks",
         f"{r}/soft.npz", "--outputs", "all"],
        ["raytrace", "masks", f"{s}/cage.toml", "-o", f"{r}/rt-cage.npz", "--outputs", "all"],
        ["raytrace", "masks", f"{s}/soft.toml", "-o", f"{r}/rt-soft.npz", "--outputs", "all"],
        ["raytrace", "render", f"{s}/cornell.toml", "-o", f"{r}/rt-whitted.png", "--max-depth",
         "2", "--png16", f"{r}/rt-whitted16.png"],
        ["raytrace", "render", f"{s}/cage.toml", "-o", f"{r}/rt-cage-whitted.png",
         "--max-depth", "2"],
        ["raytrace", "render", f"{s}/cornell.toml", "-o", f"{r}/rt-path.png", "--integrator",
         "path", "--spp", "4", "--seed", "3", "--no-progress"],
        ["raytrace", "render", f"{s}/cornell.toml", "-o", f"{r}/rt-photon.png", "--integrator",
         "photon", "--photons", "20000", "--seed", "2"],
        ["raytrace", "tree", f"{s}/cornell.toml", "--pixel", "40", "30", "--depth", "2", "-o",
         f"{r}/tree.png"],
        ["raytrace", "radiosity", f"{s}/cornell.toml", "-o", f"{r}/rt-rad.png", "--level", "1",
         "--rays", "64", "--flat", f"{r}/rt-rad-flat.png"],
        ["shadowvol", "batch", f"{s}/jobs.jsonl", "-o", f"{r}/batch", "--format", "files",
         "--workers", "1", "--no-progress"],
    ]


def run(out: Path) -> dict[str, str]:
    """Run every command into `out` (emptied first); the sha256 of each file written."""
    shutil.rmtree(out, ignore_errors=True)
    s, r = out / "scenes", out / "files"
    r.mkdir(parents=True)
    shutil.copytree(ROOT / "scenes/meshes", s / "meshes")
    for name in CARDS:
        text = (ROOT / f"scenes/{name}.toml").read_text()
        text = re.sub(r"(?m)^width = \d+", f"width = {SIZE[0]}", text)
        (s / f"{name}.toml").write_text(re.sub(r"(?m)^height = \d+", f"height = {SIZE[1]}", text))
    (s / "jobs.jsonl").write_text("".join(json.dumps(job) + "\n" for job in JOBS))
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    for tool, *args in commands(s, r):
        done = subprocess.run([sys.executable, "-m", tool, *args], cwd=ROOT, env=env,
                              capture_output=True, text=True)
        if done.returncode != 0:
            raise SystemExit(f"{tool} {' '.join(args)}: exit {done.returncode}\n{done.stderr}")
        if args[0] == "tree":   # what it prints is an output too
            (r / "tree.txt").write_text(done.stdout)
    return {p.relative_to(r).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(r.rglob("*")) if p.is_file() and p.name != "manifest.jsonl"}


def differences(got: dict[str, str], want: dict[str, str]) -> list[str]:
    """One line per file missing, added or with other bytes."""
    return ([f"missing: {n}" for n in sorted(want.keys() - got.keys())]
            + [f"added: {n}" for n in sorted(got.keys() - want.keys())]
            + [f"differs: {n}" for n in sorted(got.keys() & want.keys()) if got[n] != want[n]])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path, help="folder for the files (emptied) and digests.json")
    ap.add_argument("--against", type=Path, help="a digests.json to compare with")
    args = ap.parse_args()
    digests = run(args.out)
    (args.out / "digests.json").write_text(json.dumps(digests, indent=1, sort_keys=True) + "\n")
    print(f"{len(digests)} files; digests in {args.out / 'digests.json'}")
    if args.against is None:
        return 0
    found = differences(digests, json.loads(args.against.read_text()))
    print("\n".join(found) if found else "every file byte-identical")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
