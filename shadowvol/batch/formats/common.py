"""What the dataset layouts share: a frame's arrays (one render, plus the hard lights'
`casters` and each object's unoccluded silhouette where a layout asks), and deterministic
encoders: 16-bit PNG depth and ids, 8-bit masks, JSON, COCO's run-length encoding.

Depth PNGs hold millimetres (scene units read as metres) as uint16, rounded; 0 where nothing
is hit or the depth does not fit (over 65.535 units).  Pillow writes (H, W) uint16 as a 16-bit
grey PNG; read it back unchanged with `cv2.imread(path, cv2.IMREAD_UNCHANGED)` or
`imageio.v3.imread(path)` (Pillow's plain `Image.open(...).convert(...)` drops to 8 bits).
"""

from __future__ import annotations

import io
import json

import numpy as np
from PIL import Image

from shadowvol.scene import AreaLight, Scene, SceneError

MM_PER_UNIT = 1000.0      # scene units are read as metres; depth files hold millimetres
UINT16_MAX = 65535
# the frame arrays every layout reads: what `Worker._arrays` makes for these outputs
BASE_OUTPUTS = ["image", "masks", "depth", "object_id"]


def frame_arrays(worker, spec: dict, scene: Scene, camera, lights, *, casters: bool = False,
                 alone: bool = False) -> dict:
    """The worker's arrays of BASE_OUTPUTS, plus `casters` (K, H, W) uint64 of the hard lights
    `casters_lights` (their indices; none when the renderer refuses casters for the scene's
    objects) and `alone` (n, H, W) bool: each object's coverage drawn without the others."""
    hard = [i for i, light in enumerate(lights) if not isinstance(light, AreaLight)]
    arrays = got = None
    if casters and hard and len(hard) == len(lights):  # one render makes them all
        got = arrays = _casters(worker, dict(spec, outputs=BASE_OUTPUTS + ["casters"]), scene,
                                camera, lights)
    if arrays is None:
        arrays = worker._arrays(dict(spec, outputs=BASE_OUTPUTS), scene, camera, lights)
        if casters and hard and len(hard) < len(lights):  # casters of the hard lights alone
            got = _casters(worker, dict(spec, outputs=["casters"]), scene, camera,
                           tuple(lights[i] for i in hard))
    arrays["casters_lights"] = hard if got is not None else []
    if got is not None:
        arrays["casters"] = got["casters"]
    if alone:
        arrays["alone"] = np.stack([_alone(worker, spec, scene, camera, obj)
                                    for obj in scene.objects])
    return arrays


def _casters(worker, spec: dict, scene: Scene, camera, lights) -> dict | None:
    """The worker's arrays, or None when the renderer refuses `casters` for the number of
    objects (its limit; the layout then notes that no light has them)."""
    try:
        return worker._arrays(spec, scene, camera, lights)
    except SceneError as exc:
        if exc.key != "objects":
            raise
        return None


def _alone(worker, spec: dict, scene: Scene, camera, obj) -> np.ndarray:
    """(H, W) bool: where `obj` covers a pixel in a scene of it alone, by the frame's renderer."""
    single = scene.replace(objects=(obj,), lights=(), camera=camera)
    if spec["renderer"] == "raytrace":
        import raytrace

        return raytrace.shadow_masks(single)[1]
    from shadowvol.raster.renderer import Renderer

    with Renderer(single, worker._context()) as renderer:
        return renderer.render(spec["method"], camera=camera, lights=(),
                               outputs=("coverage",)).coverage


def depth_mm(depth: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """(H, W) float depth in scene units -> (H, W) uint16 millimetres / `scale`, rounded;
    0 where not finite or out of range."""
    value = np.asarray(depth, np.float64) * (MM_PER_UNIT / scale)
    ok = np.isfinite(value) & (value >= 0) & (value <= UINT16_MAX)
    return np.where(ok, np.round(np.where(ok, value, 0)), 0).astype(np.uint16)


def png16(pixels: np.ndarray) -> bytes:
    """A 16-bit grey PNG of (H, W) uint16 values."""
    arr = np.ascontiguousarray(pixels, dtype=np.uint16)
    buf = io.BytesIO()
    Image.fromarray(arr).save(buf, format="PNG")
    return buf.getvalue()


def mask_png(mask: np.ndarray) -> bytes:
    """An 8-bit grey PNG: 255 where `mask`, else 0."""
    buf = io.BytesIO()
    Image.fromarray(np.asarray(mask, bool).astype(np.uint8) * 255).save(buf, format="PNG")
    return buf.getvalue()


def json_bytes(value) -> bytes:
    return (json.dumps(value, indent=2, allow_nan=False) + "\n").encode()


def bbox(mask: np.ndarray) -> list[int]:
    """[x, y, w, h] of the True pixels, BOP's [-1, -1, -1, -1] when there are none."""
    ys, xs = np.nonzero(mask)
    if xs.size == 0:
        return [-1, -1, -1, -1]
    return [int(xs.min()), int(ys.min()), int(xs.max() - xs.min() + 1),
            int(ys.max() - ys.min() + 1)]


def rle(mask: np.ndarray) -> dict:
    """COCO's compressed RLE of an (H, W) bool mask, as pycocotools' `mask.encode` writes it:
    runs of the column-major pixels, zeros first, in its 6-bit text code."""
    flat = np.asarray(mask, bool).reshape(-1, order="F")
    edges = np.flatnonzero(flat[1:] != flat[:-1]) + 1
    counts = np.diff(np.concatenate([[0], edges, [flat.size]])).tolist()
    if flat.size and flat[0]:
        counts = [0] + counts
    return {"size": [int(mask.shape[0]), int(mask.shape[1])], "counts": _rle_text(counts)}


def _rle_text(counts: list[int]) -> str:
    """pycocotools' rleToString: each count (past the second, less the count two before) in
    5-bit groups, low first, 0x20 meaning more follow, plus 48."""
    out = []
    for i, x in enumerate(counts):
        if i > 2:
            x -= counts[i - 2]
        more = True
        while more:
            c = x & 0x1F
            x >>= 5
            more = x != -1 if c & 0x10 else x != 0
            out.append(chr((c | 0x20 if more else c) + 48))
    return "".join(out)


def frame_stem(spec: dict) -> str:
    """The stem of a frame's files in a layout: its index, six digits (BOP's image id)."""
    return f"{spec['index']:06d}"
