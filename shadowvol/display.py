"""Results that display themselves in a notebook (IPython's `_repr_png_`), and `show` for a row
of labelled panels.

    frame = shadowvol.render(scene)
    frame                                          # the image, in the notebook
    shadowvol.show(frame, raytrace.render(scene), frame.lit[0], labels=["raster", "ray", "lit"])

Anything `picture` accepts can be a panel: a frame (its image), a linear float RGB image,
uint8 sRGB, a bool mask (white where True), stencil counts (a heat map).  No GL here.
"""

from __future__ import annotations

import numpy as np

from shadowvol import pictures
from shadowvol.io import encode_srgb, png_bytes

SHOW_HEIGHT = 360   # default panel height in pixels


def picture(item) -> np.ndarray:
    """(H, W, 3) uint8 sRGB of one panel: a frame result (anything with an `.image`), a float
    linear RGB (H, W, 3) array, a uint8 sRGB one, a bool mask (H, W), or integer counts (H, W)
    (the stencil heat map)."""
    image = getattr(item, "image", item)
    a = np.asarray(image)
    if a.ndim == 2 and a.dtype == bool:
        return np.repeat(np.where(a, 255, 40).astype(np.uint8)[..., None], 3, axis=2)
    if a.ndim == 2 and np.issubdtype(a.dtype, np.integer):
        return pictures.heat_map(a.astype(np.int16))
    if a.ndim == 3 and a.shape[2] in (3, 4):
        a = a[..., :3]
        return a if a.dtype == np.uint8 else encode_srgb(a)
    raise TypeError(f"cannot show an array of shape {a.shape} and dtype {a.dtype}")


class Panels:
    """A row of labelled panels, shown by a notebook as one PNG (`image`: (H, W, 3) uint8)."""

    def __init__(self, image: np.ndarray):
        self.image = image

    def _repr_png_(self) -> bytes:
        return png_bytes(self.image)


def show(*items, labels=None, height: int = SHOW_HEIGHT) -> Panels:
    """The panels side by side, each scaled to `height` pixels (nearest neighbour: pixels stay
    pixels), under its label when `labels` are given."""
    from PIL import Image

    labels = list(labels) if labels is not None else [None] * len(items)
    if len(labels) != len(items):
        raise ValueError(f"{len(items)} panels but {len(labels)} labels")
    panels = []
    for item, label in zip(items, labels):
        p = picture(item)
        w = max(1, round(p.shape[1] * height / p.shape[0]))
        p = np.asarray(Image.fromarray(p).resize((w, height), Image.NEAREST))
        if label is not None:
            p = np.concatenate([pictures.text_strip(str(label), w, 28, 20), p])
        panels.append(p)
    h = max(p.shape[0] for p in panels)
    panels = [np.pad(p, ((0, h - p.shape[0]), (0, 0), (0, 0)), constant_values=255)
              for p in panels]
    return Panels(pictures.row(panels))


def frame_png(frame) -> bytes:
    """The PNG a frame result shows itself as in a notebook: its image, sRGB."""
    return png_bytes(encode_srgb(frame.image))
