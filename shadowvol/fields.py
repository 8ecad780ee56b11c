"""The frame's ground-truth fields (docs/CONVENTIONS.md, "Ground truth"), declared once for both
renderers: their names, dtypes and shapes, what is stored where nothing is hit, and what a
scene allows (GL-free, numpy only).

`facing` and `casters` are per hard light: an area light's pixel that faces only some samples
is neither lit nor blocked, so `cast = facing & ~lit` would no longer be `casters != 0`.
"""

from __future__ import annotations

import numpy as np

from shadowvol.io import GROUND_TRUTH, MASK_ARRAYS
from shadowvol.scene import AreaLight, SceneError

__all__ = ["GROUND_TRUTH", "MAX_CASTERS", "MAX_OBJECT_IDS", "PER_HARD_LIGHT", "blank",
           "check_casters", "check_hard_lights", "check_object_ids", "shape"]

MAX_CASTERS = 64          # objects `casters` can name: one uint64 word
MAX_OBJECT_IDS = 65535    # objects `object_id` can name: uint16, 0 is the background
PER_HARD_LIGHT = ("facing", "casters")
# what a field holds where nothing is hit (0 for the others)
_NOTHING = {"depth": np.inf, "distance": np.inf}


def shape(name: str, lights: int, height: int, width: int, flat: bool = False
          ) -> tuple[int, ...]:
    """The shape of field `name` in a frame of `lights` lights, (H, W) pixels; `flat`: the
    pixels as one axis, row-major (H * W)."""
    sizes = {"L": lights, "H": height, "W": width}
    out = [sizes.get(d, d) for d in MASK_ARRAYS[name][1]]
    if flat:
        at = MASK_ARRAYS[name][1].index("H")
        out[at:at + 2] = [height * width]
    return tuple(out)


def blank(name: str, shape: tuple[int, ...]) -> np.ndarray:
    """A new array of field `name`'s dtype and `shape`, holding its value for nothing hit."""
    return np.full(shape, _NOTHING.get(name, 0), MASK_ARRAYS[name][0])


def check_casters(objects: int) -> None:
    """SceneError when `objects` objects do not fit in the `casters` word."""
    if objects > MAX_CASTERS:
        raise SceneError("objects", f"casters is a {MAX_CASTERS}-bit mask, and this scene has "
                                    f"{objects} objects; ask for the other outputs, or split "
                                    "the scene")


def check_object_ids(objects: int) -> None:
    """SceneError when `objects` objects do not fit in `object_id`."""
    if objects > MAX_OBJECT_IDS:
        raise SceneError("objects", f"object_id counts up to {MAX_OBJECT_IDS} objects, and this "
                                    f"scene has {objects}")


def check_hard_lights(lights, outputs, instead: str) -> None:
    """SceneError naming the first area light of `lights` when `outputs` asks for a per hard
    light field (PER_HARD_LIGHT); `instead` says what an area light has in its place."""
    per_light = [o for o in PER_HARD_LIGHT if o in outputs]
    area = [i for i, lt in enumerate(lights) if isinstance(lt, AreaLight)]
    if area and per_light:
        raise SceneError(f"lights[{area[0]}]", f"{per_light[0]} is defined for point, spot and "
                                               f"directional lights; for an area light use "
                                               f"{instead}")
