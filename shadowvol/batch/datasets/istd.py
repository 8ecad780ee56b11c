"""`--format istd`: shadow-removal triplets in ISTD's layout (Wang et al., CVPR 2018), each job
a folder OUT/<job>/ of

    A/NNNNNN.png          the image, 8-bit sRGB (the shadow image)
    B/NNNNNN.png          the shadow mask, 8-bit grey: the largest of the lights' mattes
    C/NNNNNN.png          the shadow-free image: the same frame with every light's
                          `shadows = false` (docs/CONVENTIONS.md, "Shadow switches")
    B_light/NNNNNN_LL.png light LL's matte (scene order, two digits or more)
    istd.json             per frame: its file name, lights and masked pixels (the index)

Light i's matte at pixel p counts the samples of light i that face p (`facing_count`) and how
many of them are blocked (`facing_count - lit_count`): ceil(255 * blocked / facing), 0 where
no sample faces p.  A hard light's matte is 255 exactly at its cast shadow (`cast = facing &
~lit`), never at an attached one (the surface turned away from the light: nothing is blocked
there, and the shadow-free image is as dark); an area light's is the soft 1 - visibility of its
facing samples, rounded up so that a pixel with any blocked sample is never 0.  Where B is 0
no light has a blocked facing sample, so both images add the same terms in the same order: A
and C are equal there, bit for bit, in float and in 8 bits; inside it A <= C.  `frame` checks
both on every frame and refuses one that breaks them (a ray-traced image whose mirrors or glass
show a shadow outside the mask: render it with max_depth 0).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from shadowvol.batch.datasets import encoding
from shadowvol.batch.spec import FrameSpec
from shadowvol.checks import SceneError
from shadowvol.io import encode_srgb, png_bytes

FOLDERS = ("A", "B", "C", "B_light")
INDEX = ("istd.json",)
OUTPUTS = ("image", "masks", "facing_count")   # what the shadow image's render makes


def shadowless(lights) -> tuple:
    """The lights with `shadows` False: the shadow-free twin's lights."""
    return tuple(dataclasses.replace(light, shadows=False) for light in lights)


def arrays(worker, spec: FrameSpec, scene, camera, lights) -> dict:
    """The frame's image, masks and `facing_count`, and `shadow_free`: the image of the same
    frame with every light's shadows off, by the same renderer."""
    shadowed = worker.arrays(dataclasses.replace(spec, outputs=OUTPUTS), scene, camera, lights)
    twin = worker.arrays(dataclasses.replace(spec, outputs=("image",)), scene, camera,
                         shadowless(lights))
    shadowed["shadow_free"] = twin["image"]
    return shadowed


def mattes(lit_count: np.ndarray, facing_count: np.ndarray) -> np.ndarray:
    """(L, H, W) uint8: each light's matte, ceil(255 * (facing - lit) / facing), 0 where no
    sample faces the pixel.  lit_count, facing_count : (L, H, W) integer counts."""
    facing = np.asarray(facing_count, np.int64)
    blocked = facing - np.asarray(lit_count, np.int64)
    if (blocked < 0).any():
        raise ValueError("lit_count exceeds facing_count: the frame's counts are inconsistent")
    value = (255 * blocked + facing - 1) // np.maximum(facing, 1)
    return np.where(facing > 0, value, 0).astype(np.uint8)


def lit_counts(arrays: dict) -> np.ndarray:
    """(L, H, W) uint16: how many samples light each pixel (a hard light's `lit`, 0 or 1)."""
    counts = arrays.get("counts") or {}
    if "lit_count" in counts:
        return counts["lit_count"]
    return np.asarray(arrays["lit"], np.uint16)


def check_pair(shadowed: np.ndarray, free: np.ndarray, mask: np.ndarray) -> None:
    """Refuse a triplet whose images differ outside `mask` (H, W) or are darker shadow-free
    inside it; `shadowed`, `free` (H, W, 3) float."""
    outside = (mask == 0)[..., None]
    differ = outside & (shadowed != free)
    if differ.any():
        count = int(differ.any(-1).sum())
        raise SceneError("max_depth", f"the image differs from its shadow-free twin at "
                         f"{count} pixels outside the shadow mask (a mirror or glass shows a "
                         f"shadow); --format istd needs the direct light alone: max_depth 0")
    if (shadowed > free).any():
        raise ValueError("the shadow image is brighter than the shadow-free one inside the "
                         "mask")


def frame(spec: FrameSpec, arrays: dict, scene) -> tuple[dict[str, bytes], dict]:
    stem, job = encoding.frame_stem(spec), spec.job
    per_light = mattes(lit_counts(arrays), arrays["facing_count"])
    mask = per_light.max(axis=0) if len(per_light) else \
        np.zeros((scene.height, scene.width), np.uint8)
    shadowed, free = arrays["image"], arrays["shadow_free"]
    check_pair(shadowed, free, mask)
    name = f"{stem}.png"
    files = {f"{job}/A/{name}": png_bytes(encode_srgb(shadowed)),
             f"{job}/B/{name}": _grey_png(mask),
             f"{job}/C/{name}": png_bytes(encode_srgb(free))}
    light_files = []
    for i, matte in enumerate(per_light):
        light_files.append(f"B_light/{stem}_{i:02d}.png")
        files[f"{job}/{light_files[-1]}"] = _grey_png(matte)
    record = {"file_name": name, "lights": light_files,
              "mask_pixels": int((mask > 0).sum()), "full_pixels": int((mask == 255).sum())}
    return files, record


def _grey_png(values: np.ndarray) -> bytes:
    """An 8-bit grey PNG of (H, W) uint8 values."""
    return png_bytes(np.asarray(values, np.uint8))


def index(job: str, entries: list[tuple[FrameSpec, dict]]) -> dict[str, bytes]:
    """istd.json: the frames in frame order, each with its light mattes and mask pixels."""
    frames = [{"image_id": spec.index, **record} for spec, record in entries]
    data = {"description": f"shadowvol batch job {job}: ISTD triplets A (shadow), B (mask), "
                           "C (shadow-free)", "folders": ["A", "B", "C", "B_light"],
            "frames": frames}
    return {f"{job}/istd.json": encoding.json_bytes(data)}
