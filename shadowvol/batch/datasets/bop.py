"""`--format bop`: OUT is one BOP-scenewise dataset (bop_toolkit: bop_datasets_format.md) of
every job: job j (its place in the job file) is the scene OUT/train/{j:06d}/ (scene_camera.json,
scene_gt.json, scene_gt_info.json, rgb/, depth/, mask/, mask_visib/ and our shadow/), image id =
frame index; OUT/models/ holds one PLY (mm) per model and models_info.json, OUT/camera.json the
first frame's intrinsics (docs/formats.md).

A model is a distinct mesh (`Object.model_key`: a mesh file at one scale, or an object's own
triangles), written in its own frame (`Object.model_vertices`: the mesh file's coordinates
times its scale); its obj_id is its place in the order models are first met, job by job in the
job file, objects in scene order, so it is the same in every job and every shard.  An object's
pose (rigid, after any jitter) is in cam_R_m2c, cam_t_m2c.  Objects of category `background`
are no model and have no ground truth.
"""

from __future__ import annotations

import numpy as np

from shadowvol.batch.datasets import encoding
from shadowvol.batch.spec import FrameSpec
from shadowvol.io import encode_srgb, png_bytes
from shadowvol.scene import BACKGROUND, SceneError

FOLDERS = ("rgb", "depth", "mask", "mask_visib", "shadow")
INDEX = ("scene_camera.json", "scene_gt.json", "scene_gt_info.json")
FIRST = ("models", "camera.json")   # what the dataset's index writes under OUT
DEPTH_SCALE = 1.0   # depth PNG value * DEPTH_SCALE = millimetres
RIGID = 1e-9        # |scale - 1| of a pose BOP takes as rigid (rounding of the jitter's turns)


def root(spec: FrameSpec) -> str:
    """The scene folder of a frame: its job's place in the job file."""
    return f"train/{spec.job_index:06d}"


def shown(scene) -> list[int]:
    """The indices of the objects that are models (not of category background)."""
    return [k for k, obj in enumerate(scene.objects) if obj.label != BACKGROUND]


def _rigid(obj) -> np.ndarray:
    """(4, 4): the object's pose, which must not scale (BOP's poses are rigid)."""
    pose = np.eye(4) if obj.pose is None else obj.pose
    scale = float(np.cbrt(np.linalg.det(pose[:3, :3])))
    if abs(scale - 1.0) > RIGID:
        raise SceneError("jitter.objects.scale", f"object {obj.name!r} is scaled by {scale:.6g} "
                                                 "from its model (by the jitter, or a pose "
                                                 "given in Python): a BOP pose (cam_R_m2c, "
                                                 "cam_t_m2c) cannot scale; leave out the scale "
                                                 "jitter for --format bop")
    return pose


def frame(spec: FrameSpec, arrays: dict, scene) -> tuple[dict[str, bytes], dict]:
    stem, folder = encoding.frame_stem(spec), root(spec)
    cam = arrays["camera"]
    K = np.array(cam["K"], np.float64)
    K[:2, 2] -= 0.5  # BOP projects with OpenCV's pixel centres
    R, t = cam["world_to_camera"][:3, :3], cam["world_to_camera"][:3, 3]
    depth = encoding.depth_mm(arrays["depth"], DEPTH_SCALE)
    files = {f"{folder}/rgb/{stem}.png": png_bytes(encode_srgb(arrays["image"])),
             f"{folder}/depth/{stem}.png": encoding.png16(depth)}
    gt, info = [], []
    for g, k in enumerate(shown(scene)):
        obj = scene.objects[k]
        pose = _rigid(obj)
        full, visib = arrays["alone"][k], arrays["object_id"] == k + 1
        files[f"{folder}/mask/{stem}_{g:06d}.png"] = encoding.mask_png(full)
        files[f"{folder}/mask_visib/{stem}_{g:06d}.png"] = encoding.mask_png(visib)
        all_, seen = int(full.sum()), int(visib.sum())
        gt.append({"cam_R_m2c": (R @ pose[:3, :3]).reshape(-1).tolist(),
                   "cam_t_m2c": ((R @ pose[:3, 3] + t) * encoding.MM_PER_UNIT).tolist(),
                   "model": obj.model_key})
        info.append({"bbox_obj": encoding.bbox(full), "bbox_visib": encoding.bbox(visib),
                     "px_count_all": all_, "px_count_valid": int((full & (depth > 0)).sum()),
                     "px_count_visib": seen, "visib_fract": seen / all_ if all_ else 0.0})
    for i, lit in enumerate(arrays["lit"]):
        files[f"{folder}/shadow/{stem}_{i:06d}.png"] = encoding.mask_png(
            arrays["coverage"] & ~lit)
    camera = {"cam_K": K.reshape(-1).tolist(), "cam_R_w2c": R.reshape(-1).tolist(),
              "cam_t_w2c": (t * encoding.MM_PER_UNIT).tolist(), "depth_scale": DEPTH_SCALE}
    return files, {"camera": camera, "gt": gt, "gt_info": info,
                   "size": [scene.width, scene.height]}


def _ply(vertices: np.ndarray, faces: np.ndarray) -> bytes:
    """An ASCII PLY of (n, 3) float64 vertices and (m, 3) faces, floats as repr (exact)."""
    head = ["ply", "format ascii 1.0", f"element vertex {len(vertices)}",
            "property float x", "property float y", "property float z",
            f"element face {len(faces)}", "property list uchar int vertex_indices",
            "end_header"]
    rows = [" ".join(repr(float(x)) for x in v) for v in vertices]
    rows += ["3 " + " ".join(str(int(i)) for i in f) for f in faces]
    return ("\n".join(head + rows) + "\n").encode()


def _diameter(v: np.ndarray, rows: int = 256) -> float:
    """The largest distance between two of the (n, 3) points, `rows` points at a time."""
    best = 0.0
    for at in range(0, len(v), rows):
        gap = v[at:at + rows, None, :] - v[None, :, :]
        best = max(best, float(np.sqrt((gap ** 2).sum(-1)).max()))
    return best


def models(specs: list[FrameSpec], scene_of) -> dict[str, object]:
    """model key -> the first object met of that model, in obj_id order (job-file order of
    the specs' scenes, objects in scene order)."""
    found: dict[str, object] = {}
    seen: set[str] = set()
    for spec in specs:
        if spec.scene in seen:
            continue
        seen.add(spec.scene)
        scene = scene_of(spec.scene)
        for k in shown(scene) if scene is not None else ():
            found.setdefault(scene.objects[k].model_key, scene.objects[k])
    return found


def _model_files(found: dict) -> dict[str, bytes]:
    files, info = {}, {}
    for obj_id, obj in enumerate(found.values(), start=1):
        v = obj.model_vertices() * encoding.MM_PER_UNIT
        files[f"models/obj_{obj_id:06d}.ply"] = _ply(v, np.asarray(obj.faces))
        low, high = v.min(axis=0), v.max(axis=0)
        info[str(obj_id)] = {"diameter": _diameter(v), "min_x": float(low[0]),
                             "min_y": float(low[1]), "min_z": float(low[2]),
                             "size_x": float(high[0] - low[0]),
                             "size_y": float(high[1] - low[1]),
                             "size_z": float(high[2] - low[2])}
    files["models/models_info.json"] = encoding.json_bytes(info)
    return files


def dataset_index(specs: list[FrameSpec], made: dict[str, dict], scene_of) -> dict[str, bytes]:
    """models/, camera.json (the first made frame's intrinsics and size) and every job's
    scene_camera.json, scene_gt.json, scene_gt_info.json, keyed by image id, frame order."""
    found = models(specs, scene_of)
    ids = {key: obj_id for obj_id, key in enumerate(found, start=1)}
    files = _model_files(found)
    scenes: dict[str, tuple] = {}
    first = None
    for spec in specs:
        tables = scenes.setdefault(root(spec), ({}, {}, {}))
        record = made.get(spec.id)
        if record is None or any(g["model"] not in ids for g in record["gt"]):
            continue   # not made, or its scene could not be read again here
        first = first or record
        tables[0][str(spec.index)] = record["camera"]
        tables[1][str(spec.index)] = [{"cam_R_m2c": g["cam_R_m2c"], "cam_t_m2c": g["cam_t_m2c"],
                                       "obj_id": ids[g["model"]]} for g in record["gt"]]
        tables[2][str(spec.index)] = record["gt_info"]
    for folder, tables in scenes.items():
        files.update({f"{folder}/{rel}": encoding.json_bytes(table)
                      for rel, table in zip(INDEX, tables)})
    if first is not None:
        K = np.array(first["camera"]["cam_K"]).reshape(3, 3)
        files["camera.json"] = encoding.json_bytes(
            {"cx": float(K[0, 2]), "cy": float(K[1, 2]), "depth_scale": DEPTH_SCALE,
             "fx": float(K[0, 0]), "fy": float(K[1, 1]), "height": first["size"][1],
             "width": first["size"][0]})
    return files
