"""What `Renderer.render` returns (`RenderResult`: a `shadowvol.frame.Frame` and what the
rasterizer adds), what it can be asked for, and the check of the lights it is given."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shadowvol import frame
from shadowvol.scene import AreaLight, DirectionalLight, Light, PointLight, SpotLight

# what `render(outputs=...)` can return; the default is what the frame always returned
OUTPUTS = ("image", "image_srgb", "lit", "coverage", "stencil") + frame.GROUND_TRUTH + \
    frame.LAYERS
DEFAULT_OUTPUTS = ("image", "lit", "coverage")


@dataclass(frozen=True, eq=False, kw_only=True)
class RenderResult(frame.Frame):
    """One frame (`shadowvol.frame.Frame`: lit, coverage, lit_count, samples, the ground truth
    of docs/CONVENTIONS.md and the calibration) and what the rasterizer adds.  Each array is
    None unless asked for (`Renderer.render(outputs=...)`), but `zfail`, `samples` and
    `calibration`, always there; `lit_count` comes with `lit`.  The arrays are the caller's: a
    later frame writes only into memory nothing refers to any more (`recycle.ArrayPool`).

    image      : (H, W, 3) float32 linear RGB (direct Phong lighting; an area light's
                 samples summed: soft shadows)
    stencil    : (L, H, W) int16 signed stencil counts after each light's volume pass (hard
                 lights only)
    zfail      : (L, n_objects) bool, which casters were counted with z-fail for each light
                 (for an area light: for any of its samples)
    image_srgb : (H, W, 3) uint8, `image` encoded to sRGB on the GPU (the IEC 61966-2-1
                 curve of `shadowvol.io.encode_srgb`, in float32: a code may differ by one)
    """

    image: np.ndarray | None = None
    stencil: np.ndarray | None = None
    zfail: np.ndarray
    image_srgb: np.ndarray | None = None

    def _repr_png_(self) -> bytes:
        """A notebook shows the frame as its image."""
        from shadowvol.display import frame_png
        return frame_png(self)


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
