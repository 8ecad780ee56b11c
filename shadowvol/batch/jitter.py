"""A job's randomised scenes: `jitter.objects` moves, turns and scales each object about its
own centre, `jitter.colors` changes each material's colour; both seeded per frame.

    "jitter": {"objects": {"translation": r, "rotation": degrees, "scale": s, "axis": "up"},
               "colors": c}

- Which objects: every object whose category is not `background` (the stage stays put).
- An object's centre is the centre of its world box.  Its offset is drawn in the ball of
  radius r, its turn uniformly in [-degrees, degrees] about the up axis (+y) or, with
  "axis": "any", about a uniformly drawn axis, its scale factor uniformly in [1 - s, 1 + s]
  (s < 1).  Its pose (model to world) becomes J @ pose, J the jitter's similarity, so every
  pose written (BOP's cam_R_m2c, cam_t_m2c, the manifest's) is the jittered one.
- Colours: each object's diffuse and ambient colour times 1 + c u, u uniform in [-1, 1], one u
  per channel, the same for both (c <= 1: colours stay >= 0).
- What it guarantees: after the jitter, every moved object's world box (axis-aligned) lies at
  or above the ground, the lowest y of the scene as given, and overlaps no other object's box
  (touching is not overlapping; `GAP` of the scene's size is touching), so no object is
  inside another or below the ground by the jitter's doing.  Pairs whose boxes overlap in the
  scene as given (a ball in a bowl) are not held apart: the jitter adds no overlap the scene
  did not have.  The objects are placed one at a time, in scene order; an object is drawn
  again, up to `TRIES` times, until it fits beside the background and the objects placed
  before it; when no draw fits, the frame fails with a SceneError under `jitter.objects`.
- Determinism: the draws come from generators of (seed, frame index, 1) for the objects and
  (seed, frame index, 2) for the colours, apart from the eye's and lights' (`job_frames.jittered`),
  so a frame is the same wherever it is made, and the eye and lights move as they did before
  these keys existed.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from shadowvol.scene import (BACKGROUND, MAX_MAGNITUDE, Object, Parallelogram, Scene,
                             SceneError, Sphere, is_number, reject_unknown_keys, shorten)

OBJECT_KEYS = {"translation", "rotation", "scale", "axis"}
AXES = ("up", "any")
TRIES = 100          # draws per object before its frame fails
GAP = 1e-9           # of the scene's size: boxes closer than this touch, a box this far below
                     # the ground is on it (rounding of the box of a turned object)


def check(value) -> dict:
    """`jitter.objects` as JSON data, checked (SceneError naming the key)."""
    key = "jitter.objects"
    if not isinstance(value, dict):
        raise SceneError(key, f"expected {{\"translation\": r, \"rotation\": degrees, "
                              f"\"scale\": s, \"axis\": \"up\"|\"any\"}}, got {shorten(value)}")
    reject_unknown_keys(value, OBJECT_KEYS, key)
    out = {}
    for name, high in (("translation", math.inf), ("rotation", 180.0), ("scale", 1.0)):
        if name in value:
            x = value[name]
            ok = is_number(x) and math.isfinite(x) and 0 <= x <= high and \
                not (name == "scale" and x >= 1)
            if not ok:
                limit = {"translation": ">= 0", "rotation": "from 0 to 180 degrees",
                         "scale": "from 0 to below 1"}[name]
                raise SceneError(f"{key}.{name}", f"must be a number {limit}, got {shorten(x)}")
            if name == "translation" and x > MAX_MAGNITUDE:
                raise SceneError(f"{key}.{name}", f"a radius of {x:g} would move the objects "
                                                  f"beyond the float32 range the renderers use "
                                                  f"(|x| <= {MAX_MAGNITUDE:g})")
            out[name] = float(x)
    if "axis" in value:
        if value["axis"] not in AXES:
            raise SceneError(f"{key}.axis", f"must be \"up\" or \"any\", got "
                                            f"{shorten(value['axis'])}")
        out["axis"] = value["axis"]
    return out


def check_colors(value) -> float:
    if not is_number(value) or not math.isfinite(value) or not 0 <= value <= 1:
        raise SceneError("jitter.colors", f"must be a number from 0 to 1 (relative), got "
                                          f"{shorten(value)}")
    return float(value)


def applies(jitter: dict) -> bool:
    """Whether `jitter` changes the scene's objects (not only the eye and the lights)."""
    return "objects" in jitter or "colors" in jitter


def jittered_scene(scene: Scene, jitter: dict, seed: int, index: int) -> Scene:
    """`scene` with its objects and colours jittered for frame `index` (itself when the jitter
    has neither)."""
    if not applies(jitter):
        return scene
    objects = list(scene.objects)
    if "objects" in jitter:
        try:
            objects = _placed(objects, jitter["objects"],
                              np.random.default_rng([seed, index, 1]), scene.extent * GAP)
        except SceneError as exc:   # the job's jitter moved them, not the scene's own pose
            if exc.key.startswith("jitter."):
                raise   # already the jitter's (no place found in its draws)
            radius = jitter["objects"].get("translation", 0.0)
            raise SceneError("jitter.objects.translation", f"a radius of {radius:g} moved the "
                                                           f"objects out of range: {exc.key}: "
                                                           f"{exc.problem}") from None
    if "colors" in jitter:
        rng = np.random.default_rng([seed, index, 2])
        objects = [_recoloured(obj, 1 + jitter["colors"] * rng.uniform(-1, 1, 3))
                   for obj in objects]
    return scene.replace(objects=tuple(objects))


def _box(vertices: np.ndarray) -> np.ndarray:
    """(2, 3): the min and max corner of the points."""
    return np.stack([vertices.min(axis=0), vertices.max(axis=0)])


def _overlaps(box: np.ndarray, boxes: np.ndarray, gap: float) -> np.ndarray:
    """(m,) bool: the open box `box` (2, 3) and each of `boxes` (m, 2, 3) share a point, by
    more than `gap` on every axis."""
    return np.all(box[0] < boxes[:, 1] - gap, axis=1) & np.all(boxes[:, 0] < box[1] - gap,
                                                               axis=1)


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """(3, 3): the turn by `angle` radians about the unit `axis` (Rodrigues)."""
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)


def _draw(rng: np.random.Generator, spec: dict, centre: np.ndarray) -> np.ndarray:
    """(4, 4): one draw of the jitter about `centre`: translation, turn, scale, always the
    same number of draws from `rng`."""
    direction = rng.normal(size=3)
    direction /= np.linalg.norm(direction) or 1.0
    offset = direction * spec.get("translation", 0.0) * rng.uniform() ** (1 / 3)
    axis = rng.normal(size=3)
    if spec.get("axis", "up") == "up":
        axis = np.array([0.0, 1.0, 0.0])
    else:
        axis /= np.linalg.norm(axis) or 1.0
    angle = math.radians(spec.get("rotation", 0.0)) * rng.uniform(-1, 1)
    factor = 1 + spec.get("scale", 0.0) * rng.uniform(-1, 1)
    m = np.eye(4)
    m[:3, :3] = factor * _rotation(axis, angle)
    m[:3, 3] = centre + offset - m[:3, :3] @ centre
    return m


def _placed(objects: list[Object], spec: dict, rng: np.random.Generator,
            gap: float) -> list[Object]:
    boxes = np.stack([_box(obj.vertices) for obj in objects])   # (n, 2, 3)
    ground = float(boxes[:, 0, 1].min())
    moving = [k for k, obj in enumerate(objects) if obj.label != BACKGROUND]
    placed = np.array([obj.label == BACKGROUND for obj in objects])   # the stage, then each
    final = boxes.copy()                                              # object once placed
    for k in moving:
        obj, centre = objects[k], boxes[k].mean(axis=0)
        # the objects to keep clear of: placed, and apart from it in the scene as given
        others = final[placed & ~_overlaps(boxes[k], boxes, gap)]
        for _ in range(TRIES):
            m = _draw(rng, spec, centre)
            vertices = obj.vertices @ m[:3, :3].T + m[:3, 3]
            box = _box(vertices)
            if box[0, 1] >= ground - gap and not _overlaps(box, others, gap).any():
                break
        else:
            raise SceneError("jitter.objects", f"object {obj.name!r}: none of {TRIES} draws "
                                               f"keeps its box above the ground (y >= "
                                               f"{ground:g}) and clear of the other objects' "
                                               "boxes; make the jitter smaller")
        objects[k] = _moved(obj, m, vertices)
        final[k] = box
        placed[k] = True
    return objects


def _moved(obj: Object, m: np.ndarray, vertices: np.ndarray) -> Object:
    """`obj` moved by the similarity `m` (4, 4): its vertices (given), exact shape, pose; its
    model stays the one it was an instance of."""
    pose = m if obj.pose is None else m @ obj.pose
    analytic = obj.analytic
    linear = m[:3, :3]
    if isinstance(analytic, Sphere):
        analytic = Sphere(linear @ analytic.center + m[:3, 3],
                          analytic.radius * float(np.cbrt(np.linalg.det(linear))))
    elif isinstance(analytic, Parallelogram):
        analytic = Parallelogram(linear @ analytic.origin + m[:3, 3], linear @ analytic.edge_u,
                                 linear @ analytic.edge_v)
    return dataclasses.replace(obj, vertices=vertices, pose=pose, analytic=analytic,
                               model=obj.model_key)


def _recoloured(obj: Object, factor: np.ndarray) -> Object:
    material = dataclasses.replace(obj.material, diffuse=obj.material.diffuse * factor,
                                   ambient=obj.material.ambient * factor)
    return dataclasses.replace(obj, material=material, model=obj.model_key)
