"""`--format coco`: OUT/<job>/annotations.json (COCO instance annotations) and
OUT/<job>/images/NNNNNN.png; image id = frame index.

Two category sets: object k (the object_id k, scene order) is category k, supercategory
"object"; the cast shadow of object k under light i is category SHADOW_IDS * (i + 1) + k,
supercategory "shadow": the pixels where object k lies on the shadow segment to light i
(`casters` bit (k - 1) mod 64 of word (k - 1) div 64: for an area light, object k blocks
some sample facing the pixel).  Every light has them (`info.shadow_lights` lists them).
Segmentations are compressed RLE, column-major, as pycocotools' `mask.encode` writes them (decode with `pycocotools.mask.decode`); iscrowd 0.
"""

from __future__ import annotations

import numpy as np

from shadowvol.batch.formats import encoding
from shadowvol.batch.spec import FrameSpec
from shadowvol.io import encode_srgb, png_bytes

FOLDERS = ("images",)
INDEX = ("annotations.json",)
SHADOW_IDS = 1 << 16   # above every object id (object_id is uint16)


def _instance(category: int, mask: np.ndarray) -> dict:
    return {"category_id": category, "segmentation": encoding.rle(mask),
            "area": int(mask.sum()), "bbox": encoding.bbox(mask), "iscrowd": 0}


def frame(spec: FrameSpec, arrays: dict, scene) -> tuple[dict[str, bytes], dict]:
    stem, ids = encoding.frame_stem(spec), arrays["object_id"]
    image = f"images/{stem}.png"
    files = {f"{spec.job}/{image}": png_bytes(encode_srgb(arrays["image"]))}
    found = []
    for k in range(1, len(scene.objects) + 1):
        mask = ids == k
        if mask.any():
            found.append(_instance(k, mask))
    for slot, light in enumerate(arrays["casters_lights"]):
        words = arrays["casters"][slot]   # (H, W, K)
        for k in range(1, len(scene.objects) + 1):
            word, bit = divmod(k - 1, 64)
            mask = (words[..., word] >> np.uint64(bit)) & np.uint64(1) != 0
            if mask.any():
                found.append(_instance(SHADOW_IDS * (light + 1) + k, mask))
    record = {"image": {"file_name": image, "width": scene.width, "height": scene.height},
              "objects": [obj.name for obj in scene.objects], "lights": len(scene.lights),
              "shadow_lights": list(arrays["casters_lights"]), "annotations": found}
    return files, record


def _categories(record: dict) -> list[dict]:
    names = record["objects"]
    out = [{"id": k, "name": name, "supercategory": "object"}
           for k, name in enumerate(names, start=1)]
    out += [{"id": SHADOW_IDS * (i + 1) + k, "name": f"{name} shadow, light {i}",
             "supercategory": "shadow"}
            for i in record["shadow_lights"] for k, name in enumerate(names, start=1)]
    return out


def index(job: str, entries: list[tuple[FrameSpec, dict]]) -> dict[str, bytes]:
    """annotations.json: images and annotations in frame order, annotation ids from 1."""
    first = entries[0][1] if entries else {"objects": [], "shadow_lights": []}
    images, annotations = [], []
    for spec, record in entries:
        images.append({"id": spec.index, **record["image"]})
        for found in record["annotations"]:
            annotations.append({"id": len(annotations) + 1, "image_id": spec.index,
                                **found})
    data = {"info": {"description": f"shadowvol batch job {job}",
                     "shadow_lights": first["shadow_lights"]},
            "images": images, "categories": _categories(first), "annotations": annotations}
    return {f"{job}/annotations.json": encoding.json_bytes(data)}
