"""What a batch frame can write: one entry per output, data-driven.

Each output names the arrays it needs from a frame (`fields`), the suffix of its file
(`OUT/<job>/<frame>.<suffix>`, or the member `<job>/<frame>.<suffix>` of a webdataset tar) and
its encoder (arrays -> bytes, deterministic: `shadowvol.io`).  A new output of the renderers
(depth, normals, object ids, ...) is one more entry here; jobs, the workers, the manifest, resume
and the webdataset shards take it from this table.  `fields` are attributes of a frame's result
(`Renderer.render(...)`), or the ray tracer's arrays of the same names (`batch.worker`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from shadowvol.frame import GROUND_TRUTH, LAYERS, masks_bytes
from shadowvol.io import encode_srgb, npy_bytes, png_bytes


@dataclass(frozen=True)
class Output:
    name: str
    suffix: str                      # after "<frame>.": no "/", the first "." splits the key
    fields: tuple[str, ...]          # the frame arrays `encode` reads
    encode: Callable[[dict[str, np.ndarray]], bytes]
    description: str


OUTPUTS: dict[str, Output] = {o.name: o for o in (
    Output("image", "png", ("image",), lambda f: png_bytes(encode_srgb(f["image"])),
           "the image, 8-bit sRGB PNG, row 0 at the top"),
    Output("masks", "masks.npz", ("lit", "coverage", "camera", "light_samples", "counts"),
           lambda f: masks_bytes(f["lit"], f["coverage"], arrays=f["camera"] | f["counts"],
                                 light_samples=f["light_samples"]),
           "the shadow masks (docs/CONVENTIONS.md): lit (L, H, W) bool, coverage (H, W) bool, "
           "the camera matrices and lights (K, world_to_camera, camera_to_world, ...), each "
           "area light's samples and, when a light has more than one, lit_count (L, H, W) "
           "uint16 and samples (L,) int64, as every mask file holds them"),
    # the ground truth (docs/CONVENTIONS.md): one .npy each, from either renderer
    *(Output(name, f"{name}.npy", (name,), lambda f, name=name: npy_bytes(f[name]),
             f"the ground truth's {name} (docs/CONVENTIONS.md), a .npy of its array")
      for name in GROUND_TRUTH),
    # the intrinsic layers (docs/CONVENTIONS.md): one float32 .npy each, from either renderer
    *(Output(name, f"{name}.npy", (name,), lambda f, name=name: npy_bytes(f[name]),
             f"the intrinsic layer {name} (docs/CONVENTIONS.md), a float32 .npy")
      for name in LAYERS),
)}

DEFAULT = ("image", "masks")


def fields_of(names) -> tuple[str, ...]:
    """The frame arrays the outputs `names` need, each once, in a fixed order."""
    seen: dict[str, None] = {}
    for name in names:
        for field in OUTPUTS[name].fields:
            seen.setdefault(field, None)
    return tuple(seen)
