"""The frame's ground-truth fields (docs/CONVENTIONS.md, "Ground truth"), declared once for both
renderers: their names, dtypes and shapes, what is stored where nothing is hit, and what a
scene allows (GL-free, numpy only).

Every field is defined for every light kind: an area light is its N samples, each a hard
light, and its per-light fields reduce theirs (counts add, `casters` ORs).
"""

from __future__ import annotations

import numpy as np

from shadowvol.io import GROUND_TRUTH, MASK_ARRAYS
from shadowvol.scene import SceneError

__all__ = ["CASTER_WORD_BITS", "GROUND_TRUTH", "MAX_OBJECT_IDS", "blank", "caster_words",
           "check_object_ids", "decode_casters", "shape"]

CASTER_WORD_BITS = 64     # objects per uint64 word of `casters`
MAX_OBJECT_IDS = 65535    # objects `object_id` can name: uint16, 0 is the background
# what a field holds where nothing is hit (0 for the others)
_NOTHING = {"depth": np.inf, "distance": np.inf}


def caster_words(objects: int) -> int:
    """K, the uint64 words of `casters` per pixel for a scene of `objects` objects: object j
    is bit j mod 64 of word j div 64."""
    return max(1, -(-objects // CASTER_WORD_BITS))


def shape(name: str, lights: int, height: int, width: int, flat: bool = False,
          objects: int = 0) -> tuple[int, ...]:
    """The shape of field `name` in a frame of `lights` lights, (H, W) pixels and `objects`
    objects; `flat`: the pixels as one axis, row-major (H * W)."""
    sizes = {"L": lights, "H": height, "W": width, "K": caster_words(objects)}
    out = [sizes.get(d, d) for d in MASK_ARRAYS[name][1]]
    if flat:
        at = MASK_ARRAYS[name][1].index("H")
        out[at:at + 2] = [height * width]
    return tuple(out)


def blank(name: str, shape: tuple[int, ...]) -> np.ndarray:
    """A new array of field `name`'s dtype and `shape`, holding its value for nothing hit."""
    return np.full(shape, _NOTHING.get(name, 0), MASK_ARRAYS[name][0])


def decode_casters(casters: np.ndarray, objects: int) -> np.ndarray:
    """(..., K) uint64 `casters` -> (..., objects) bool, element j: scene.objects[j] casts
    (numpy alone: the words' bytes, little-endian, unpacked lowest bit first)."""
    bits = np.unpackbits(np.ascontiguousarray(casters, "<u8").view(np.uint8), axis=-1,
                         bitorder="little")
    return bits[..., :objects].astype(bool)


def check_object_ids(objects: int) -> None:
    """SceneError when `objects` objects do not fit in `object_id`."""
    if objects > MAX_OBJECT_IDS:
        raise SceneError("objects", f"object_id counts up to {MAX_OBJECT_IDS} objects, and this "
                                    f"scene has {objects}")
