"""`--format bop`: each job a BOP-scenewise dataset (bop_toolkit: bop_datasets_format.md)
of one scene, OUT/<job>/train/000000/ (scene_camera.json, scene_gt.json, scene_gt_info.json,
rgb/, depth/, mask/, mask_visib/ and our shadow/), image id = frame index, with OUT/<job>/models/
(PLY, mm, and models_info.json) and camera.json written with frame 0 (docs/formats.md).

An object's model frame is world axes with its origin at the centre of the object's box, so
cam_R_m2c is cam_R_w2c and cam_t_m2c = R_w2c c + t_w2c; `mask` is the object drawn alone.
"""

from __future__ import annotations

import numpy as np

from shadowvol.batch.formats import encoding
from shadowvol.batch.spec import FrameSpec
from shadowvol.io import encode_srgb, png_bytes

SCENE = "train/000000"
FOLDERS = tuple(f"{SCENE}/{sub}" for sub in ("rgb", "depth", "mask", "mask_visib", "shadow"))
INDEX = tuple(f"{SCENE}/{name}" for name in
              ("scene_camera.json", "scene_gt.json", "scene_gt_info.json"))
FIRST = ("models", "")   # folders of what frame 0 adds: the models, camera.json
DEPTH_SCALE = 1.0   # depth PNG value * DEPTH_SCALE = millimetres


def _centre(obj) -> np.ndarray:
    v = np.asarray(obj.vertices, np.float64)
    return (v.min(axis=0) + v.max(axis=0)) / 2


def frame(spec: FrameSpec, arrays: dict, scene) -> tuple[dict[str, bytes], dict]:
    stem, root = encoding.frame_stem(spec), f"{spec.job}/{SCENE}"
    cam = arrays["camera"]
    K = np.array(cam["K"], np.float64)
    K[:2, 2] -= 0.5  # BOP projects with OpenCV's pixel centres
    R, t = cam["world_to_camera"][:3, :3], cam["world_to_camera"][:3, 3]
    depth = encoding.depth_mm(arrays["depth"], DEPTH_SCALE)
    files = {f"{root}/rgb/{stem}.png": png_bytes(encode_srgb(arrays["image"])),
             f"{root}/depth/{stem}.png": encoding.png16(depth)}
    gt, info = [], []
    for k, obj in enumerate(scene.objects):
        full, visib = arrays["alone"][k], arrays["object_id"] == k + 1
        files[f"{root}/mask/{stem}_{k:06d}.png"] = encoding.mask_png(full)
        files[f"{root}/mask_visib/{stem}_{k:06d}.png"] = encoding.mask_png(visib)
        all_, seen = int(full.sum()), int(visib.sum())
        gt.append({"cam_R_m2c": R.reshape(-1).tolist(),
                   "cam_t_m2c": ((R @ _centre(obj) + t) * encoding.MM_PER_UNIT).tolist(),
                   "obj_id": k + 1})
        info.append({"bbox_obj": encoding.bbox(full), "bbox_visib": encoding.bbox(visib),
                     "px_count_all": all_, "px_count_valid": int((full & (depth > 0)).sum()),
                     "px_count_visib": seen, "visib_fract": seen / all_ if all_ else 0.0})
    for i, lit in enumerate(arrays["lit"]):
        files[f"{root}/shadow/{stem}_{i:06d}.png"] = encoding.mask_png(arrays["coverage"] & ~lit)
    if spec.index == 0:
        files.update(_models(spec.job, scene, K))
    camera = {"cam_K": K.reshape(-1).tolist(), "cam_R_w2c": R.reshape(-1).tolist(),
              "cam_t_w2c": (t * encoding.MM_PER_UNIT).tolist(), "depth_scale": DEPTH_SCALE}
    return files, {"camera": camera, "gt": gt, "gt_info": info}


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


def _models(job: str, scene, K: np.ndarray) -> dict[str, bytes]:
    """Each object's mesh in its model frame (mm), models_info.json and camera.json."""
    files, info = {}, {}
    for k, obj in enumerate(scene.objects):
        v = (np.asarray(obj.vertices, np.float64) - _centre(obj)) * encoding.MM_PER_UNIT
        files[f"{job}/models/obj_{k + 1:06d}.ply"] = _ply(v, np.asarray(obj.faces))
        low, high = v.min(axis=0), v.max(axis=0)
        diameter = _diameter(v)
        info[str(k + 1)] = {"diameter": diameter, "min_x": float(low[0]),
                            "min_y": float(low[1]), "min_z": float(low[2]),
                            "size_x": float(high[0] - low[0]), "size_y": float(high[1] - low[1]),
                            "size_z": float(high[2] - low[2])}
    files[f"{job}/models/models_info.json"] = encoding.json_bytes(info)
    files[f"{job}/camera.json"] = encoding.json_bytes(
        {"cx": float(K[0, 2]), "cy": float(K[1, 2]), "depth_scale": DEPTH_SCALE,
         "fx": float(K[0, 0]), "fy": float(K[1, 1]), "height": scene.height,
         "width": scene.width})
    return files


def index(job: str, entries: list[tuple[FrameSpec, dict]]) -> dict[str, bytes]:
    """scene_camera.json, scene_gt.json, scene_gt_info.json: keyed by image id, frame order."""
    tables = ({}, {}, {})
    for spec, record in entries:
        for table, part in zip(tables, ("camera", "gt", "gt_info")):
            table[str(spec.index)] = record[part]
    return {f"{job}/{rel}": encoding.json_bytes(table) for rel, table in zip(INDEX, tables)}
