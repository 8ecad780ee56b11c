"""`--format coco`: OUT/<job>/annotations.json (COCO instance annotations of the job's frames),
OUT/<job>/images/NNNNNN.png, and OUT/annotations.json, the same of every job in one file.

One category table for the whole dataset: the classes (`Object.label`: an object's category,
else its name), numbered from 1 in the order they are first met, job by job in the job file,
objects in scene order, so a class has one id in every job and every shard; supercategory
"object".  The cast shadow of class c under light i is category SHADOW_IDS * (i + 1) + c,
supercategory "shadow"; an object's shadow annotation is the pixels where it lies on the shadow
segment to light i (`casters` bit (k - 1) mod 64 of word (k - 1) div 64, k its object_id: for an
area light, it blocks some sample facing the pixel).  Every light has them
(`info.shadow_lights` lists them).  Objects of category `background` are not annotated.
Image ids are the frames' places among the dataset's frames (job-file order), annotation ids
count from 1 over the dataset: both unique in the dataset, so the jobs' files merge as they are.
Segmentations are compressed RLE, column-major, as pycocotools' `mask.encode` writes them
(decode with `pycocotools.mask.decode`); iscrowd 0.
"""

from __future__ import annotations

import numpy as np

from shadowvol.batch.datasets import encoding
from shadowvol.batch.spec import FrameSpec
from shadowvol.io import encode_srgb, png_bytes
from shadowvol.scene import BACKGROUND

FOLDERS = ("images",)
INDEX = ("annotations.json",)
FIRST = ("annotations.json",)   # what the dataset's index writes under OUT
SHADOW_IDS = 1 << 16   # above every class id (object_id is uint16)


def _instance(k: int, light: int | None, mask: np.ndarray) -> dict:
    return {"object": k, "light": light, "segmentation": encoding.rle(mask),
            "area": int(mask.sum()), "bbox": encoding.bbox(mask), "iscrowd": 0}


def frame(spec: FrameSpec, arrays: dict, scene) -> tuple[dict[str, bytes], dict]:
    stem, ids = encoding.frame_stem(spec), arrays["object_id"]
    image = f"images/{stem}.png"
    files = {f"{spec.job}/{image}": png_bytes(encode_srgb(arrays["image"]))}
    labels = [obj.label for obj in scene.objects]
    shown = [k for k in range(1, len(labels) + 1) if labels[k - 1] != BACKGROUND]
    found = []
    for k in shown:
        mask = ids == k
        if mask.any():
            found.append(_instance(k, None, mask))
    for slot, light in enumerate(arrays["casters_lights"]):
        words = arrays["casters"][slot]   # (H, W, K)
        for k in shown:
            word, bit = divmod(k - 1, 64)
            mask = (words[..., word] >> np.uint64(bit)) & np.uint64(1) != 0
            if mask.any():
                found.append(_instance(k, light, mask))
    record = {"image": {"file_name": image, "width": scene.width, "height": scene.height},
              "labels": labels, "lights": len(scene.lights),
              "shadow_lights": list(arrays["casters_lights"]), "annotations": found}
    return files, record


def classes(specs: list[FrameSpec], made: dict[str, dict], scene_of) -> tuple[list[str], int]:
    """(the class names in id order, the most lights of a frame): from the specs' scenes, in
    job-file order (a scene that cannot be loaded: its made frames' labels)."""
    names: dict[str, None] = {}
    lights = 0
    for spec in specs:
        scene = scene_of(spec.scene)
        if scene is not None:
            labels = [obj.label for obj in scene.objects]
            lights = max(lights, len(scene.lights) if spec.lights is None else len(spec.lights))
        else:
            record = made.get(spec.id) or {"labels": [], "lights": 0}
            labels, lights = record["labels"], max(lights, record["lights"])
        names.update((label, None) for label in labels if label != BACKGROUND)
    return list(names), lights


def _categories(names: list[str], lights: int) -> list[dict]:
    out = [{"id": c, "name": name, "supercategory": "object"}
           for c, name in enumerate(names, start=1)]
    out += [{"id": SHADOW_IDS * (i + 1) + c, "name": f"{name} shadow, light {i}",
             "supercategory": "shadow"}
            for i in range(lights) for c, name in enumerate(names, start=1)]
    return out


def dataset_index(specs: list[FrameSpec], made: dict[str, dict], scene_of) -> dict[str, bytes]:
    """Every job's annotations.json and OUT/annotations.json: images and annotations in frame
    order, the dataset's categories in each."""
    names, lights = classes(specs, made, scene_of)
    categories = _categories(names, lights)
    ids = {name: c for c, name in enumerate(names, start=1)}
    jobs: dict[str, dict] = {}
    everything = {"images": [], "annotations": []}
    count = 0
    for image_id, spec in enumerate(specs):
        job = jobs.setdefault(spec.job, {"images": [], "annotations": [], "shadow_lights": None})
        record = made.get(spec.id)
        if record is None:
            continue
        if job["shadow_lights"] is None:
            job["shadow_lights"] = record["shadow_lights"]
        job["images"].append({"id": image_id, **record["image"]})
        everything["images"].append({"id": image_id, **record["image"],
                                     "file_name": f"{spec.job}/{record['image']['file_name']}"})
        for found in record["annotations"]:
            count += 1
            c = ids[record["labels"][found["object"] - 1]]
            category = c if found["light"] is None else SHADOW_IDS * (found["light"] + 1) + c
            ann = {"id": count, "image_id": image_id, "category_id": category,
                   **{key: found[key] for key in ("segmentation", "area", "bbox", "iscrowd")}}
            job["annotations"].append(ann)
            everything["annotations"].append(ann)
    files = {}
    for name, job in jobs.items():
        files[f"{name}/annotations.json"] = encoding.json_bytes(
            {"info": {"description": f"shadowvol batch job {name}",
                      "shadow_lights": job["shadow_lights"] or []},
             "images": job["images"], "categories": categories,
             "annotations": job["annotations"]})
    files["annotations.json"] = encoding.json_bytes(
        {"info": {"description": "shadowvol batch dataset: every job",
                  "shadow_lights": list(range(lights))},
         "images": everything["images"], "categories": categories,
         "annotations": everything["annotations"]})
    return files
