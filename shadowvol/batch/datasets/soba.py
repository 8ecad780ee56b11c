"""`--format soba` and `--format soba-lights`: instance shadows in SOBA's annotation JSON (Wang et
al., "Instance Shadow Detection", CVPR 2020; read by `pysobatools.soba.SOBA`, a fork of
pycocotools' COCO), each job OUT/<job>/annotations.json and OUT/<job>/images/NNNNNN.png;
image id = frame index (docs/formats.md).

    categories        [{"id": 1, "name": "Object"}, {"id": 2, "name": "Shadow"}]
    association       [{"id": 1, "name": "Object-Shadow"}]: the association categories, under
                      the key SOBA's loader reads (`dataset['association']`)
    annotations       an object and its shadow per pair, each with `association`: the pair's
                      id within its image, from 1 (SOAPeval reads 0 as "no pair")
    association_anno  per pair the object's pixels OR its shadow's, category 1, `association`
                      and `light`

An object's shadow is exactly the pixels its `casters` bit marks (docs/CONVENTIONS.md: it
blocks some facing sample of the light; pixels on the object itself included): `soba` merges
the lights (the bit of any light; one pair per object, `light` lists the lights whose bit is
set somewhere in it), `soba-lights` keeps them apart (one pair per object and light, `light`
[i], the object's annotation repeated in each).  A pair needs both halves in view: an object
with no visible shadow, or a shadow whose object is out of view, has none.  The background (an
object of category "background", as a floor plane is by default: docs/formats.md) is never an
instance and gets no pair, nor does an object whose `cast_shadows` is false (it casts nothing,
so no shadow of its is in the image).  Segmentations are
compressed RLE, as pycocotools' `mask.encode` writes them; iscrowd 0.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from shadowvol.batch.datasets import encoding
from shadowvol.batch.spec import FrameSpec
from shadowvol.io import encode_srgb, png_bytes
from shadowvol.scene import BACKGROUND

FOLDERS = ("images",)
INDEX = ("annotations.json",)
OBJECT, SHADOW, ASSOCIATION = 1, 2, 1
CATEGORIES = [{"id": OBJECT, "name": "Object", "supercategory": "object"},
              {"id": SHADOW, "name": "Shadow", "supercategory": "shadow"}]
ASSOCIATIONS = [{"id": ASSOCIATION, "name": "Object-Shadow", "supercategory": "association"}]
OUTPUTS = ("image", "object_id", "casters")


def arrays(worker, spec: FrameSpec, scene, camera, lights) -> dict:
    """The frame's image, `object_id` and every light's `casters`."""
    return worker.arrays(dataclasses.replace(spec, outputs=OUTPUTS), scene, camera, lights)


def caster_bit(casters: np.ndarray, j: int) -> np.ndarray:
    """(..., H, W) bool: bit j (object j, from 0) of (..., H, W, K) uint64 `casters`."""
    word, bit = divmod(j, 64)
    return (casters[..., word] >> np.uint64(bit)) & np.uint64(1) != 0


def _instance(category: int, mask: np.ndarray) -> dict:
    return {"category_id": category, "segmentation": encoding.rle(mask),
            "area": int(mask.sum()), "bbox": encoding.bbox(mask), "iscrowd": 0}


def pairs(object_id: np.ndarray, casters: np.ndarray, objects, per_light: bool):
    """(object j, light indices, object mask, shadow mask) of every pair, objects in scene
    order (and lights in scene order within an object, per light)."""
    found = []
    for j, obj in enumerate(objects):
        seen = object_id == j + 1
        if not obj.cast_shadows or obj.label == BACKGROUND or not seen.any():
            continue
        bits = caster_bit(casters, j)   # (L, H, W)
        shadows = [([i], bits[i]) for i in range(len(bits))] if per_light else \
            [([i for i in range(len(bits)) if bits[i].any()], bits.any(axis=0))]
        found += [(j, lights, seen, shadow) for lights, shadow in shadows if shadow.any()]
    return found


def frame(spec: FrameSpec, arrays: dict, scene, *, per_light: bool
          ) -> tuple[dict[str, bytes], dict]:
    image = f"images/{encoding.frame_stem(spec)}.png"
    files = {f"{spec.job}/{image}": png_bytes(encode_srgb(arrays["image"]))}
    found = []
    for j, lights, seen, shadow in pairs(arrays["object_id"], arrays["casters"],
                                         scene.objects, per_light):
        found.append({"object": j, "light": lights, "instances": [
            _instance(OBJECT, seen), _instance(SHADOW, shadow)],
            "association": _instance(ASSOCIATION, seen | shadow)})
    record = {"image": {"file_name": image, "width": scene.width, "height": scene.height},
              "objects": [obj.name for obj in scene.objects], "pairs": found}
    return files, record


def index(job: str, entries: list[tuple[FrameSpec, dict]]) -> dict[str, bytes]:
    """annotations.json: images, annotations and association_anno in frame order, each list's
    ids from 1; association ids from 1 within each image."""
    images, annotations, associations = [], [], []
    for spec, record in entries:
        images.append({"id": spec.index, **record["image"]})
        for pair_id, pair in enumerate(record["pairs"], start=1):
            shared = {"image_id": spec.index, "association": pair_id}
            for instance in pair["instances"]:
                extra = {"light": pair["light"]} if instance["category_id"] == SHADOW else {}
                annotations.append({"id": len(annotations) + 1, **shared, **instance, **extra,
                                    "object_id": pair["object"] + 1})
            associations.append({"id": len(associations) + 1, **shared, **pair["association"],
                                 "light": pair["light"], "object_id": pair["object"] + 1})
    data = {"info": {"description": f"shadowvol batch job {job}: SOBA instance shadows"},
            "images": images, "categories": CATEGORIES, "association": ASSOCIATIONS,
            "annotations": annotations, "association_anno": associations}
    return {f"{job}/annotations.json": encoding.json_bytes(data)}
