"""Small scenes and paths shared by the tests (the one builders module; tests never import
from each other).  Vary a built scene with `dataclasses.replace` / `Scene.replace`."""

from __future__ import annotations

import json
import math
from pathlib import Path

from shadowvol.primitives import plane
from shadowvol.scene import Camera, DirectionalLight, Scene

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "scenes"
TEST_OUTPUT = ROOT / "test-output"
MODELS = ROOT.parent / "shared" / "models"


def tiny_scene(with_blocker_behind_eye: bool = False) -> Scene:
    camera = Camera(eye=[0, 0, 5], target=[0, 0, 0], fov_y=math.degrees(2 * math.atan(0.2)))
    objects = [plane("backdrop", point=[0, 0, -5], normal=[0, 0, 1], size=[20, 20]),
               plane("A", point=[-1.45, 0, -4], normal=[0, 0, 1], size=[1.1, 4]),
               plane("B", point=[-2.45, 0, -3], normal=[0, 0, 1], size=[1.1, 4])]
    if with_blocker_behind_eye:
        # behind the camera, out of view, between the eye and the light: the eye is in its
        # shadow volume, no visible point is
        objects.append(plane("roof", point=[-3, 0, 8], normal=[0, 0, 1], size=[4, 10]))
    return Scene(camera=camera, objects=objects,
                 lights=[DirectionalLight(direction=[1, 0, -1])], width=4, height=4)


# ---- batch jobs (tests/batch) ----------------------------------------------------------

def job_lines(frames: int = 4, size=(40, 30), raytrace: bool = True) -> list[dict]:
    """A turntable of the cage scene (rasterized) and, optionally, two ray-traced frames of it
    with a light override and jitter: every kind of job field the runs must agree on."""
    jobs = [{"name": "cage-turntable", "scene": str(SCENES / "cage.toml"), "size": list(size),
             "cameras": {"orbit": {"center": [-0.6, 1.0, -0.8], "radius": 7.0,
                                   "elevation": 30.0, "start": 20.0, "sweep": 60.0,
                                   "frames": frames}},
             "outputs": ["image", "masks"]}]
    if raytrace:
        jobs.append({"name": "cage-traced", "scene": str(SCENES / "cage.toml"),
                     "size": [24, 18], "renderer": "raytrace", "max_depth": 1, "seed": 7,
                     "jitter": {"eye": 0.2, "lights": 0.1},
                     "lights": [{"type": "point", "position": [0.0, 1.4, 0.0]},
                                {"type": "directional", "direction": [-0.3, -1.0, -0.4],
                                 "intensity": 0.5}],
                     "cameras": [{"eye": [4.2, 3.4, 5.2], "target": [-0.6, 1.0, -0.8]},
                                 {"eye": [3.0, 2.0, 6.0], "target": [-0.6, 1.0, -0.8],
                                  "fov_y": 40.0}]})
    return jobs


def write_jobs(path: Path, jobs: list, extra_lines: tuple[str, ...] = ()) -> Path:
    path.write_text("".join(json.dumps(j) + "\n" for j in jobs) +
                    "".join(line + "\n" for line in extra_lines))
    return path


def output_files(out: Path) -> dict[str, bytes]:
    """Every file under `out` but the manifests, by relative path, with its bytes."""
    return {p.relative_to(out).as_posix(): p.read_bytes() for p in sorted(out.rglob("*"))
            if p.is_file() and not p.name.startswith("manifest")}


def manifest_hashes(out: Path, name: str = "manifest.jsonl") -> list[tuple]:
    """(id, output, sha256) of every file the manifest lists, and each record's error, in
    manifest order: what must not depend on how the frames were made."""
    rows = []
    for line in (out / name).read_text().splitlines():
        record = json.loads(line)
        if "files" in record:
            rows += [(record["id"], k, v["sha256"]) for k, v in record["files"].items()]
        elif "tar" in record:
            rows.append((record["id"], "tar", record["sha256"]))
        else:
            rows.append((record["id"], "error", record["error"]))
    return rows
