"""The frames of a job: cameras from a list, an orbit (turntable) or a path of key poses;
stable ids; the seeded per-frame generator; the frame specs the workers render.

A frame spec is a `spec.FrameSpec` (typed, frozen, of JSON data), made in the parent from the
job alone, so that every process given it renders the same frame: its id `<job>/<index:06d>`,
the camera, the light overrides, the size, the outputs, the renderer and its options, the seed
and jitter.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math

import numpy as np

from shadowvol.batch.spec import FrameSpec
from shadowvol.scene import (LOOK_AT_CAMERA_KEYS, MIXED_FORMS, AreaLight, Camera,
                             DirectionalLight, SceneError, is_number, reject_unknown_keys,
                             shorten)
from shadowvol.scenefile import CAMERA_KEYS, MATRIX_CAMERA_KEYS

ORBIT_KEYS = {"center", "radius", "elevation", "frames", "start", "sweep", "up", "fov_y",
              "near"}
MAX_FRAMES = 10_000_000


def frame_id(job: str, index: int) -> str:
    """The stable id of frame `index` of `job`: also its file stem, `OUT/<job>/<index:06d>.*`."""
    return f"{job}/{index:06d}"


def _finite(x) -> bool:
    """A real number that is finite as a float64 (an integer of 1e400 is not)."""
    try:
        return is_number(x) and math.isfinite(x)
    except OverflowError:
        return False


def _vector(value, key: str) -> list[float]:
    if not (isinstance(value, list) and len(value) == 3 and all(_finite(x) for x in value)):
        raise SceneError(key, f"expected 3 finite numbers, got {shorten(value)}")
    return [float(x) for x in value]


def _number(value, key: str, low: float | None = None) -> float:
    if not _finite(value) or (low is not None and value < low):
        raise SceneError(key, f"expected a finite number{'' if low is None else f' >= {low}'}, "
                              f"got {shorten(value)}")
    return float(value)


def _count(value, key: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_FRAMES:
        raise SceneError(key, f"must be a whole number from 1 to {MAX_FRAMES}, got "
                              f"{shorten(value)}")
    return value


def _optics(table: dict, key: str) -> dict:
    """The optional camera keys up, fov_y, near of `table`, checked."""
    out = {}
    if "up" in table:
        out["up"] = _vector(table["up"], f"{key}.up")
    for name in ("fov_y", "near"):
        if name in table:
            out[name] = _number(table[name], f"{key}.{name}")
    return out


def camera_dict(value, key: str, matrices: bool = True) -> dict:
    """One camera of a job: eye and target, and up/fov_y/near where given (the scene's fov_y,
    near and up fill what is left out, in the worker); or, with `matrices`, fx, fy, cx, cy,
    camera_to_world and near where given (`Camera`'s matrix form).  Checked by building the
    Camera."""
    if not isinstance(value, dict):
        raise SceneError(key, f"expected a camera table, got {shorten(value)}")
    given = [k for k in MATRIX_CAMERA_KEYS if k in value]
    if given and matrices:
        return _matrix_camera(value, key, given)
    reject_unknown_keys(value, CAMERA_KEYS - set(MATRIX_CAMERA_KEYS), key)   # look-at only
    for need in ("eye", "target"):
        if need not in value:
            raise SceneError(f"{key}.{need}", "missing")
    cam = {"eye": _vector(value["eye"], f"{key}.eye"),
           "target": _vector(value["target"], f"{key}.target"), **_optics(value, key)}
    try:
        Camera(**cam)
    except SceneError as exc:
        raise exc.under(key) from None
    return cam


def _matrix_camera(value: dict, key: str, given: list[str]) -> dict:
    """A camera of intrinsics and pose: fx, fy, cx, cy, camera_to_world, near where given."""
    look_at = [k for k in LOOK_AT_CAMERA_KEYS if k in value]
    if look_at:
        raise SceneError(f"{key}.{given[0]}", f"given with {look_at[0]}: {MIXED_FORMS}")
    reject_unknown_keys(value, set(MATRIX_CAMERA_KEYS) | {"near"}, key)
    for need in MATRIX_CAMERA_KEYS:
        if need not in value:
            raise SceneError(f"{key}.{need}", "missing (a camera given by intrinsics needs "
                                              "fx, fy, cx, cy and camera_to_world)")
    cam = {name: _number(value[name], f"{key}.{name}") for name in ("fx", "fy", "cx", "cy")}
    if "near" in value:
        cam["near"] = _number(value["near"], f"{key}.near")
    try:
        camera = Camera(**cam, camera_to_world=value["camera_to_world"])
    except SceneError as exc:
        raise exc.under(key) from None
    return {**cam, "camera_to_world": camera.camera_to_world.tolist()}


def orbit(value) -> tuple[dict, ...]:
    """A turntable: `frames` eyes on a circle of `radius` around `center` (y up) at
    `elevation` degrees, starting at azimuth `start` (0: on +z) and turning `sweep` degrees
    (default 360, so the last frame is one step short of the first), all looking at `center`."""
    key = "cameras.orbit"
    if not isinstance(value, dict):
        raise SceneError(key, f"expected a table, got {shorten(value)}")
    reject_unknown_keys(value, ORBIT_KEYS, key)
    for need in ("center", "radius", "frames"):
        if need not in value:
            raise SceneError(f"{key}.{need}", "missing")
    center = np.array(_vector(value["center"], f"{key}.center"))
    radius = _number(value["radius"], f"{key}.radius", low=0.0)
    if radius == 0:
        raise SceneError(f"{key}.radius", "must be > 0")
    elevation = math.radians(_number(value.get("elevation", 0.0), f"{key}.elevation"))
    if abs(elevation) >= math.pi / 2:
        raise SceneError(f"{key}.elevation", "must be strictly between -90 and 90 degrees")
    n = _count(value["frames"], f"{key}.frames")
    start = _number(value.get("start", 0.0), f"{key}.start")
    sweep = _number(value.get("sweep", 360.0), f"{key}.sweep")
    optics = _optics(value, key)
    cameras = []
    for i in range(n):
        azimuth = math.radians(start + sweep * i / n)
        offset = radius * np.array([math.cos(elevation) * math.sin(azimuth), math.sin(elevation),
                                    math.cos(elevation) * math.cos(azimuth)])
        cameras.append({"eye": (center + offset).tolist(), "target": center.tolist(), **optics})
    return tuple(cameras)


def path(value) -> tuple[dict, ...]:
    """`frames` cameras along key poses: eye, target, up and fov_y linearly interpolated
    between consecutive keys, the first frame at the first key and the last at the last."""
    key = "cameras.path"
    if not isinstance(value, dict) or set(value) - {"keys", "frames"}:
        raise SceneError(key, f"expected {{\"keys\": [camera, ...], \"frames\": n}}, got "
                              f"{shorten(value)}")
    keys = value.get("keys")
    if not isinstance(keys, list) or len(keys) < 2:
        raise SceneError(f"{key}.keys", "expected a list of at least 2 cameras")
    poses = [camera_dict(c, f"{key}.keys[{i}]", matrices=False) for i, c in enumerate(keys)]
    for name in ("up", "fov_y", "near"):
        if len({name in p for p in poses}) != 1:
            raise SceneError(f"{key}.keys", f"give {name} in every key or in none")
    n = _count(value.get("frames"), f"{key}.frames")
    cameras = []
    for i in range(n):
        t = 0.0 if n == 1 else i * (len(poses) - 1) / (n - 1)
        k = min(int(t), len(poses) - 2)
        a, b, u = poses[k], poses[k + 1], t - k
        cam = {name: (np.array(a[name]) * (1 - u) + np.array(b[name]) * u).tolist()
               for name in ("eye", "target", "up") if name in a}
        if "fov_y" in a:
            cam["fov_y"] = a["fov_y"] * (1 - u) + b["fov_y"] * u
        if "near" in a:
            cam["near"] = a["near"]
        cameras.append(camera_dict(cam, f"{key} frame {i}", matrices=False))
    return tuple(cameras)


def frame_rng(seed: int, index: int) -> np.random.Generator:
    """The generator of frame `index` of a job seeded `seed`: depends on nothing else (not on
    the worker, the shard or the order frames are made in)."""
    return np.random.default_rng([seed, index])


def _in_ball(rng: np.random.Generator, radius: float) -> np.ndarray:
    direction = rng.normal(size=3)
    direction /= np.linalg.norm(direction) or 1.0
    return direction * radius * rng.uniform() ** (1 / 3)


def jittered(camera: Camera, lights: tuple, jitter: dict, seed: int, index: int):
    """(camera, lights) of a frame with `jitter` applied: the eye (a look-at camera's eye, its
    target kept; a matrix camera's whole pose, its axes kept), then each point/spot light's
    position and each area light's centre (the whole emitter: its samples move with it), moved
    by offsets drawn in that order from `frame_rng(seed, index)`."""
    if not jitter:
        return camera, lights
    import dataclasses

    rng = frame_rng(seed, index)
    offset = _in_ball(rng, jitter.get("eye", 0.0))
    with _jitter_named("eye", jitter, "the eye"):
        if camera.matrix_form:   # the whole pose moves: a matrix camera has no target to keep
            camera = camera.translated(offset)
        else:
            camera = dataclasses.replace(camera, eye=camera.eye + offset)
    moved = []
    for i, light in enumerate(lights):
        with _jitter_named("lights", jitter, f"lights[{i}]"):
            if isinstance(light, DirectionalLight):
                moved.append(light)
            elif isinstance(light, AreaLight):
                moved.append(dataclasses.replace(
                    light, center=light.center + _in_ball(rng, jitter.get("lights", 0.0))))
            else:
                moved.append(dataclasses.replace(
                    light, position=light.position + _in_ball(rng, jitter.get("lights", 0.0))))
    return camera, tuple(moved)


@contextlib.contextmanager
def _jitter_named(key: str, jitter: dict, what: str):
    """A jittered eye or light the model refuses (past float32) is the job's `jitter.<key>`'s
    fault: the SceneError names that key and what it moved, not the model's own key."""
    try:
        yield
    except SceneError as exc:
        radius = jitter.get(key, 0.0)
        raise SceneError(f"jitter.{key}", f"a radius of {radius:g} moved {what} out of range: "
                                          f"{exc.key}: {exc.problem}") from None


def specs(job, scene_key: str) -> list[FrameSpec]:
    """The frame specs of a checked `jobs.Job`, in index order."""
    return [FrameSpec(id=frame_id(job.name, i), index=i, job=job.name, scene=scene_key,
                      camera=camera,
                      lights=None if job.lights is None else tuple(job.lights),
                      size=None if job.size is None else tuple(job.size),
                      outputs=tuple(job.outputs), renderer=job.renderer, method=job.method,
                      max_depth=job.max_depth, seed=job.seed, jitter=dict(job.jitter))
            for i, camera in enumerate(job.cameras)]


def spec_hash(spec: FrameSpec, scene_sha256: str) -> str:
    """sha256 of everything that decides a frame's files: the spec and the scene file's bytes
    (a mesh file that changes under an unchanged scene file is not seen)."""
    text = json.dumps({**spec.as_dict(), "scene": scene_sha256}, sort_keys=True,
                      separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()
