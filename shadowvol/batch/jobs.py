"""Batch jobs: a JSONL file (one JSON object a line) or the same objects as Python dicts.

    {"name": "cage-turntable", "scene": "cage.toml", "size": [160, 120],
     "cameras": {"orbit": {"center": [0, 1, 0], "radius": 7, "elevation": 25, "frames": 8}},
     "outputs": ["image", "masks"], "renderer": "shadowvol", "seed": 0}

Keys (only `scene` and `cameras` are required):
- name: the job's name, [A-Za-z0-9_-], at most 64 characters; its frames' ids are
  `<name>/<index:06d>`.  Default: the scene file's name without its suffix.
- scene: a scene file (relative to the job file's folder), or from Python a `Scene`.
- cameras: a list of cameras ({"eye", "target", and optionally "up", "fov_y", "near": the
  scene camera's where left out}, or {"fx", "fy", "cx", "cy", "camera_to_world"[, "near"]}:
  intrinsics in pixels of the job's size and a pose, as a scene file's camera), or
  {"orbit": {...}} (a turntable, `job_frames.orbit`), or {"path": {"keys": [camera, ...],
  "frames": n}} (look-at key poses, linearly interpolated).
- lights: a list of lights in the scene-file schema ([[lights]] tables), replacing the scene's.
- size: [width, height] of the images (default: the scene's).
- outputs: names from `batch.outputs.OUTPUTS` (default: image and masks).
- renderer: "shadowvol" (default) or "raytrace"; or "auto" for a job whose outputs are the
  masks alone: per frame the renderer `shadowvol.compare.fastest` says is faster on the worker
  (the frame's manifest line says which, as `masks_by`); method: auto|zpass|zfail
  (shadowvol); max_depth: the ray tracer's recursion (default: the scene's).
- seed (default 0) and jitter: {"eye": r, "lights": r} moves each frame's eye and point/spot
  lights by a random offset within a ball of radius r, drawn from the frame's own generator
  (`job_frames.frame_rng(seed, index)`), so a frame is the same wherever and whenever it is made;
  {"objects": {"translation", "rotation", "scale", "axis"}, "colors": c} moves, turns, scales
  and recolours the objects (`batch.jitter`, which says what it guarantees).

A job that is wrong is a `JobError` in the list, recorded in the manifest; the others go on.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from shadowvol.batch import job_frames
from shadowvol.batch import jitter
from shadowvol.batch.outputs import DEFAULT, OUTPUTS
from shadowvol.raster.methods import METHODS
from shadowvol.scene import (
    MAX_MAGNITUDE,
    Scene,
    SceneError,
    is_number,
    reject_unknown_keys,
    shorten,
)
from shadowvol.scenefile import MAX_NESTING, check_shape, light_from_dict
from shadowvol.scenefile_mesh import check_regular_file, read_regular_file

KEYS = {"name", "scene", "cameras", "lights", "size", "outputs", "renderer", "method",
        "max_depth", "seed", "jitter"}
RENDERERS = ("shadowvol", "raytrace", "auto")
NAME = re.compile(r"[A-Za-z0-9_-]{1,64}")
MAX_JOB_FILE_BYTES = 64 << 20
MAX_FRAMES_PER_JOB = 10_000_000


@dataclass(frozen=True)
class Job:
    """One checked job.  `cameras` are plain dicts (eye, target and what the job gave), the
    same in every process; `scene` is an absolute path or a Scene."""

    name: str
    scene: str | Scene
    cameras: tuple[dict, ...]
    lights: tuple[dict, ...] | None = None
    size: tuple[int, int] | None = None
    outputs: tuple[str, ...] = DEFAULT
    renderer: str = "shadowvol"
    method: str = "auto"
    max_depth: int | None = None
    seed: int = 0
    jitter: dict = field(default_factory=dict)
    source: str = ""  # where it came from, for messages: "jobs.jsonl:3"


@dataclass(frozen=True)
class JobError:
    """A job that could not be read: its name (or `line-N`), where it is, and why."""

    name: str
    source: str
    error: str


def read_jobs(path: str | Path) -> list[Job | JobError]:
    """The jobs of a JSONL file, in file order; blank lines and lines starting with `#` are
    skipped.  A file that cannot be read is a SceneError; a bad line is a JobError."""
    path = Path(path)
    try:  # a regular file only (a FIFO or a device is refused unread), at most the cap
        text = read_regular_file(path, MAX_JOB_FILE_BYTES, what="the job file").decode("utf-8")
    except UnicodeDecodeError as exc:
        raise SceneError("", f"not UTF-8 text: {exc}", str(path)) from None
    except SceneError as exc:
        raise exc.in_file(str(path)) from None
    entries = []
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        source = f"{path}:{number}"
        try:
            data = json.loads(line)
        except json.JSONDecodeError as exc:
            entries.append(JobError(f"line-{number}", source, f"not valid JSON: {exc}"))
            continue
        except RecursionError:  # json's parser recurses once a level
            entries.append(JobError(f"line-{number}", source,
                                    f"nested more than {MAX_NESTING} levels deep"))
            continue
        if not isinstance(data, dict):
            entries.append(JobError(f"line-{number}", source, "a job must be a JSON object"))
            continue
        entries.append((data, source, path.parent))
    return check_jobs(entries)


def check_jobs(entries, base_dir: str | Path = ".") -> list[Job | JobError]:
    """Jobs from dicts (or (dict, source, base_dir) triples, as `read_jobs` makes them):
    each checked, names made unique (a second job of one name is a JobError)."""
    out: list[Job | JobError] = []
    taken: dict[str, str] = {}
    for i, entry in enumerate(entries):
        if isinstance(entry, (Job, JobError)):
            job = entry
        else:
            data, source, where = entry if isinstance(entry, tuple) else \
                (entry, f"jobs[{i}]", Path(base_dir))
            job = _job(data, source, where, i)
        if isinstance(job, Job) and job.name in taken:
            job = JobError(f"{job.name}@{job.source}", job.source,
                           f"name: {job.name!r} is also the name of the job at "
                           f"{taken[job.name]}; give each job its own name")
        if isinstance(job, Job):
            taken[job.name] = job.source
        out.append(job)
    return out


def _job(data: dict, source: str, base_dir: Path, position: int) -> Job | JobError:
    fallback = data.get("name") if isinstance(data.get("name"), str) else f"job-{position}"
    try:
        check_shape(data)  # nesting and list lengths, iteratively: never a RecursionError
        reject_unknown_keys(data, KEYS)
        scene = data.get("scene")
        if isinstance(scene, Scene):
            default_name = scene.name
        elif isinstance(scene, (str, Path)) and str(scene):
            given_path = base_dir / scene
            scene = str(given_path.resolve())
            default_name = Path(scene).stem
            # refused now, by stat alone: its digest and its loader must never wait on a FIFO
            check_regular_file(Path(scene), "scene", f"the scene file {given_path}")
        else:
            raise SceneError("scene", f"expected a scene file name, got {shorten(scene)}")
        name = data.get("name", re.sub(r"[^A-Za-z0-9_-]+", "_", default_name)[:64] or "job")
        if not isinstance(name, str) or not NAME.fullmatch(name):
            raise SceneError("name", f"must be 1-64 letters, digits, '_' or '-', got "
                                     f"{shorten(name)}")
        fallback = name
        outputs = _outputs(data.get("outputs", list(DEFAULT)))
        job = Job(name=name, scene=scene, cameras=_cameras(data.get("cameras")),
                  lights=_lights(data.get("lights")), size=_size(data.get("size")),
                  outputs=outputs, renderer=_renderer(data.get("renderer", "shadowvol"), outputs),
                  method=_choice(data.get("method", "auto"), "method", METHODS),
                  max_depth=_whole(data.get("max_depth"), "max_depth", low=0),
                  seed=_whole(data.get("seed", 0), "seed", low=0),
                  jitter=_jitter(data.get("jitter", {})), source=source)
    except SceneError as exc:
        return JobError(fallback, source, str(exc))
    return job


def _cameras(value) -> tuple[dict, ...]:
    if isinstance(value, list):
        if not value:
            raise SceneError("cameras", "the list is empty")
        return tuple(job_frames.camera_dict(c, f"cameras[{i}]") for i, c in enumerate(value))
    if isinstance(value, dict) and len(value) == 1 and "orbit" in value:
        return job_frames.orbit(value["orbit"])
    if isinstance(value, dict) and len(value) == 1 and "path" in value:
        return job_frames.path(value["path"])
    raise SceneError("cameras", f"expected a list of cameras, {{\"orbit\": {{...}}}} or "
                                f"{{\"path\": {{...}}}}, got {shorten(value)}")


def _lights(value) -> tuple[dict, ...] | None:
    if value is None:
        return None
    if not isinstance(value, list):
        raise SceneError("lights", f"expected a list of lights, got {shorten(value)}")
    for i, light in enumerate(value):
        light_from_dict(light, f"lights[{i}]")  # checked here, built in the worker
    return tuple(value)


def _size(value) -> tuple[int, int] | None:
    if value is None:
        return None
    if not (isinstance(value, list) and len(value) == 2):
        raise SceneError("size", f"expected [width, height], got {shorten(value)}")
    return (_whole(value[0], "size[0]", low=1), _whole(value[1], "size[1]", low=1))


def _outputs(value) -> tuple[str, ...]:
    if not isinstance(value, list) or not value:
        raise SceneError("outputs", f"expected a list of output names, got {shorten(value)}")
    for name in value:
        if name not in OUTPUTS:
            raise SceneError("outputs", f"unknown output {shorten(name)} (the outputs are: "
                                        f"{', '.join(OUTPUTS)})")
    if len(set(value)) != len(value):
        raise SceneError("outputs", f"an output is named twice in {value}")
    return tuple(value)


def _renderer(value, outputs: tuple[str, ...]) -> str:
    """The job's renderer; "auto" only for the masks alone (what both renderers make alike)."""
    renderer = _choice(value, "renderer", RENDERERS)
    if renderer == "auto" and outputs != ("masks",):
        raise SceneError("renderer", f"auto chooses the renderer of the masks alone (outputs "
                                     f"[\"masks\"]), got outputs {list(outputs)}: name "
                                     f"shadowvol or raytrace")
    return renderer


def _choice(value, key: str, allowed: tuple[str, ...]) -> str:
    if value not in allowed:
        raise SceneError(key, f"must be one of {', '.join(allowed)}, got {shorten(value)}")
    return value


def _whole(value, key: str, low: int):
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise SceneError(key, f"must be a whole number >= {low}, got {shorten(value)}")
    return value


def _jitter(value) -> dict:
    if not isinstance(value, dict) or set(value) - {"eye", "lights", "objects", "colors"}:
        raise SceneError("jitter", f"expected {{\"eye\": r, \"lights\": r, \"objects\": "
                                   f"{{...}}, \"colors\": c}}, got {shorten(value)}")
    out = {}
    for key, r in value.items():
        if key == "objects":
            out[key] = jitter.check(r)
        elif key == "colors":
            out[key] = jitter.check_colors(r)
        elif not is_number(r) or not math.isfinite(r) or r < 0:
            raise SceneError(f"jitter.{key}", f"must be a radius >= 0, got {shorten(r)}")
        else:
            if r > MAX_MAGNITUDE:
                raise SceneError(f"jitter.{key}", f"a radius of {r:g} would move the {key} "
                                                  f"beyond the float32 range the renderers use "
                                                  f"(|x| <= {MAX_MAGNITUDE:g})")
            out[key] = float(r)
    return out
