"""What `Renderer.render` returns (`RenderResult`) and the checks of what it is asked for."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shadowvol import fields
from shadowvol.cameras import Calibration
from shadowvol.io import GroundTruthFrame
from shadowvol.scene import AreaLight, DirectionalLight, Light, PointLight, SpotLight

SILHOUETTES = ("cpu", "gpu")
# what `render(outputs=...)` can return; the default is what the frame always returned
OUTPUTS = ("image", "image_srgb", "lit", "coverage", "stencil") + fields.GROUND_TRUTH
DEFAULT_OUTPUTS = ("image", "lit", "coverage")


@dataclass(frozen=True, eq=False)
class RenderResult(GroundTruthFrame):
    """One frame.  Each array is None unless asked for (`Renderer.render(outputs=...)`).
    The arrays are the caller's: a later frame writes only into memory nothing refers to any
    more (`recycle.ArrayPool`).

    image      : (H, W, 3) float32 linear RGB (direct Phong lighting; an area light's
                 samples summed: soft shadows)
    lit        : (L, H, W) bool, per light: covered, stencil 0, n . l > 0, inside the spot
                 cone; for an area light: so for every sample (lit_count == N)
    coverage   : (H, W) bool, geometry visible at the pixel centre
    stencil    : (L, H, W) int16 signed stencil counts after each light's volume pass (hard
                 lights only)
    zfail      : (L, n_objects) bool, which casters were counted with z-fail for each light
                 (for an area light: for any of its samples; always returned)
    lit_count  : (L, H, W) uint16, per light how many of its samples (hard lights: 1) light
                 the pixel as `lit` says (returned with `lit`)
    samples    : (L,) int64, N per light (hard lights: 1; always returned)
    image_srgb : (H, W, 3) uint8, `image` encoded to sRGB on the GPU (the IEC 61966-2-1
                 curve of `shadowvol.io.encode_srgb`, in float32: a code may differ by one)
    depth, distance, normal, object_id, facing, facing_count, casters : the ground truth
                 of docs/CONVENTIONS.md (see `truth`), when asked for; casters (L, H, W, K)
    calibration : the camera matrices and light arrays of the frame (always)
    """

    image: np.ndarray | None
    lit: np.ndarray | None
    coverage: np.ndarray | None
    stencil: np.ndarray | None
    zfail: np.ndarray
    lit_count: np.ndarray | None = None
    samples: np.ndarray | None = None
    image_srgb: np.ndarray | None = None
    depth: np.ndarray | None = None
    distance: np.ndarray | None = None
    normal: np.ndarray | None = None
    object_id: np.ndarray | None = None
    facing: np.ndarray | None = None
    facing_count: np.ndarray | None = None
    casters: np.ndarray | None = None
    calibration: Calibration | None = None


    @property
    def visibility(self) -> np.ndarray:
        """(L, H, W) float32: lit_count / N."""
        return (self.lit_count / self.samples[:, None, None]).astype(np.float32)

    def _repr_png_(self) -> bytes:
        """A notebook shows the frame as its image."""
        from shadowvol.display import frame_png
        return frame_png(self)


def check_outputs(outputs, stencil: bool) -> set[str]:
    """`outputs=` of render: names from OUTPUTS (default DEFAULT_OUTPUTS); `stencil=True`
    adds "stencil"."""
    if outputs is None:
        outputs = DEFAULT_OUTPUTS
    if isinstance(outputs, str):
        raise TypeError(f"outputs must be a sequence of names, e.g. ({outputs!r},)")
    chosen = set(outputs)
    unknown = sorted(chosen - set(OUTPUTS))
    if unknown:
        raise ValueError(f"unknown output {unknown[0]!r}; outputs are {', '.join(OUTPUTS)}")
    return chosen | ({"stencil"} if stencil else set())


def check_lights(lights) -> tuple[Light, ...] | None:
    """`lights=` of render and volume_view: None (the scene's) or Light objects; anything else
    (light indices, say) is a TypeError rather than a frame without those lights."""
    if lights is None:
        return None
    lights = tuple(lights)
    bad = [x for x in lights
           if not isinstance(x, (PointLight, DirectionalLight, SpotLight, AreaLight))]
    if bad:
        raise TypeError(f"lights must be Light objects (e.g. scene.lights[0]), got {bad[0]!r}")
    return lights
