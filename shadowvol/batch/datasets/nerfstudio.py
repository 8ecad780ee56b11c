"""`--format nerfstudio`: OUT/<job>/transforms.json and the frames' files beside it.

    images/NNNNNN.png      the image, 8-bit sRGB          (file_path)
    depth/NNNNNN.png       eye-space depth, 16-bit mm     (depth_file_path; nerfstudio's
                           default depth_unit_scale_factor 1e-3 reads it back in scene units)
    masks/NNNNNN.png       coverage, 8-bit, 255 = geometry (mask_path: nerfstudio ignores 0)
    object_id/NNNNNN.png   object ids, 16-bit              (object_id_path, ours)
    shadow/NNNNNN_LL.png   light LL's lit mask, 8-bit      (lit_paths, ours)

`transform_matrix` is our `camera_to_world`: OpenGL camera axes (x right, y up, looking down
-z) to world, nerfstudio's convention; fl_x, fl_y, cx, cy are K's, whose pixel centres are at
+0.5, nerfstudio's convention too.  camera_model "OPENCV" with zero distortion.
"""

from __future__ import annotations

from shadowvol.batch.datasets import encoding
from shadowvol.batch.spec import FrameSpec
from shadowvol.io import encode_srgb, png_bytes

FOLDERS = ("images", "depth", "masks", "object_id", "shadow")
INDEX = ("transforms.json",)
INTRINSICS = ("fl_x", "fl_y", "cx", "cy", "w", "h")


def frame(spec: FrameSpec, arrays: dict, scene) -> tuple[dict[str, bytes], dict]:
    stem, job = encoding.frame_stem(spec), spec.job
    cam = arrays["camera"]
    K = cam["K"]
    paths = {"file_path": f"images/{stem}.png", "depth_file_path": f"depth/{stem}.png",
             "mask_path": f"masks/{stem}.png", "object_id_path": f"object_id/{stem}.png"}
    files = {paths["file_path"]: png_bytes(encode_srgb(arrays["image"])),
             paths["depth_file_path"]: encoding.png16(encoding.depth_mm(arrays["depth"])),
             paths["mask_path"]: encoding.mask_png(arrays["coverage"]),
             paths["object_id_path"]: encoding.png16(arrays["object_id"])}
    lit_paths = []
    for i, lit in enumerate(arrays["lit"]):
        lit_paths.append(f"shadow/{stem}_{i:02d}.png")
        files[lit_paths[-1]] = encoding.mask_png(lit)
    record = {**paths, "lit_paths": lit_paths,
              "transform_matrix": cam["camera_to_world"].tolist(),
              "fl_x": float(K[0, 0]), "fl_y": float(K[1, 1]), "cx": float(K[0, 2]),
              "cy": float(K[1, 2]), "w": scene.width, "h": scene.height}
    return {f"{job}/{rel}": data for rel, data in files.items()}, record


def index(job: str, entries: list[tuple[FrameSpec, dict]]) -> dict[str, bytes]:
    """transforms.json: the first frame's intrinsics on top, a frame's own where they differ
    (a path of key poses can change fov_y)."""
    top = {name: entries[0][1][name] for name in INTRINSICS} if entries else {}
    frames = []
    for _, record in entries:
        own = {name: record[name] for name in INTRINSICS if record[name] != top[name]}
        frames.append({"file_path": record["file_path"],
                       "transform_matrix": record["transform_matrix"],
                       "depth_file_path": record["depth_file_path"],
                       "mask_path": record["mask_path"],
                       "object_id_path": record["object_id_path"],
                       "lit_paths": record["lit_paths"], **own})
    transforms = {"camera_model": "OPENCV", **top, "k1": 0.0, "k2": 0.0, "p1": 0.0, "p2": 0.0,
                  "depth_unit_scale_factor": 1.0 / encoding.MM_PER_UNIT, "frames": frames}
    return {f"{job}/transforms.json": encoding.json_bytes(transforms)}
