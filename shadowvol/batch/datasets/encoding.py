"""The layouts' deterministic encoders: 16-bit PNG depth and ids, 8-bit masks, JSON, COCO's
run-length encoding, boxes.

Depth PNGs hold millimetres (scene units read as metres) as uint16, rounded; 0 where nothing
is hit or the depth does not fit (over 65.535 units).  Pillow writes (H, W) uint16 as a 16-bit
grey PNG; read it back unchanged with `cv2.imread(path, cv2.IMREAD_UNCHANGED)`,
`imageio.v3.imread(path)` or `np.asarray(Image.open(path))` (`.convert(...)` drops to 8 bits).
"""

from __future__ import annotations

import io
import json

import numpy as np
from PIL import Image

from shadowvol.batch.spec import FrameSpec

MM_PER_UNIT = 1000.0      # scene units are read as metres; depth files hold millimetres
UINT16_MAX = 65535


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


def frame_stem(spec: FrameSpec) -> str:
    """The stem of a frame's files in a layout: its index, six digits (BOP's image id)."""
    return f"{spec.index:06d}"
