"""A shadow map measured against the exact shadow: which pixels it gets wrong, and how.

The frame is the shadow-volume renderer's (its `lit` is exact: the witness's masks agree with
it away from edges), and the shadow map (`shadowvol.raster.shadowmap`) is asked about the same
visible points: the pixel centres' surface points, from the frame's depth.  Compared are the
pixels that face the light (and lie in a spot light's cone): there only a shadow can make them
dark.  There the shadow map's mistakes are

    acne          : lit in truth, shadowed by the map (a surface shadowing itself)
    peter_panning : shadowed in truth, lit by the map (a shadow come loose, or gone)

and `misclassified` is their sum.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shadowvol.cameras import camera_to_world, intrinsics, unproject
from shadowvol.pictures import legible_rows, tint
from shadowvol.io import encode_srgb
from shadowvol.raster import shadowmap
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import DirectionalLight, Scene, SpotLight

ACNE_COLOUR = np.array([230, 40, 40], np.uint8)
PETER_PANNING_COLOUR = np.array([40, 110, 255], np.uint8)
SHADOW_COLOUR = np.array([0, 0, 0], np.uint8)


@dataclass(frozen=True, eq=False)
class ShadowMapError:
    """One light's shadow map against the exact shadow, per pixel (H, W) bool."""

    image: np.ndarray          # (H, W, 3) float32, the frame (shadow volumes)
    compared: np.ndarray       # covered, facing the light, in its cone
    lit_exact: np.ndarray
    lit_map: np.ndarray
    resolution: int
    bias: float
    pcf: int

    @property
    def acne(self) -> np.ndarray:
        return self.compared & self.lit_exact & ~self.lit_map

    @property
    def peter_panning(self) -> np.ndarray:
        return self.compared & ~self.lit_exact & self.lit_map

    def counts(self) -> dict:
        acne, peter = int(self.acne.sum()), int(self.peter_panning.sum())
        return {"resolution": self.resolution, "bias": self.bias, "pcf": self.pcf,
                "pixels": int(self.compared.sum()), "misclassified": acne + peter,
                "acne": acne, "peter_panning": peter}

    def picture(self) -> np.ndarray:
        """(H', W', 3) uint8: the shadow map's shadow | the exact shadow | the difference."""
        base = encode_srgb(self.image)
        by_map = tint(base, self.compared & ~self.lit_map, SHADOW_COLOUR, 0.6)
        exact = tint(base, self.compared & ~self.lit_exact, SHADOW_COLOUR, 0.6)
        diff = tint(tint(base, self.acne, ACNE_COLOUR, 0.85), self.peter_panning,
                    PETER_PANNING_COLOUR, 0.85)
        c = self.counts()
        return legible_rows([[
            (f"shadow map {self.resolution}^2, bias {self.bias:g}, PCF {self.pcf}", by_map),
            ("exact (shadow volumes)", exact),
            (f"acne {c['acne']} (red), peter-panning {c['peter_panning']} (blue)", diff)]])


class ShadowMapper:
    """One frame of `scene` (rendered once) and its visible points, asked of shadow maps of
    any resolution, bias and filter (`measure`).  Owns a `Renderer`: call `release()`, or use
    it as a context manager.  `ctx`: a GL context to borrow (default: a new one)."""

    def __init__(self, scene: Scene, light: int = 0, ctx=None):
        if not 0 <= light < len(scene.lights):
            raise ValueError(f"the scene has {len(scene.lights)} lights (0..{len(scene.lights) - 1}), "
                             f"not {light}")
        self.scene, self.index, self.light = scene, light, scene.lights[light]
        self.renderer = Renderer(scene, ctx)
        frame = self.renderer.render(outputs=("image", "lit", "coverage", "depth", "normal"))
        self.image = frame.image
        points = unproject(intrinsics(scene.camera, scene.width, scene.height),
                           camera_to_world(scene.camera), frame.depth)
        self.compared = frame.coverage & self._facing(points, frame.normal)
        self.lit_exact = frame.lit[light] & self.compared
        self.points = points[self.compared]
        if not len(self.points):
            raise ValueError(f"no visible point faces light {light}: nothing to compare")
        self.view = shadowmap.fit(scene, self.light, self.points)
        self._last = (0, None)   # (resolution, depth map): a sweep over biases draws it once

    def _facing(self, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
        light = self.light
        if isinstance(light, DirectionalLight):
            to_light = np.broadcast_to(-np.asarray(light.direction, float), points.shape)
        else:
            to_light = np.asarray(light.position, float) - points
        with np.errstate(invalid="ignore"):
            out = np.einsum("hwi,hwi->hw", normals.astype(float), to_light) > 0
            if isinstance(light, SpotLight):
                unit = -to_light / np.linalg.norm(to_light, axis=-1, keepdims=True)
                out &= unit @ np.asarray(light.direction, float) >= light.cos_cutoff
        return out & np.isfinite(points).all(axis=-1)

    def measure(self, resolution: int, bias: float, pcf: int = 1) -> ShadowMapError:
        """The map of `resolution` texels a side, its `bias` and K x K filter (`pcf`), against
        the exact shadow (the map drawn once for calls in a row at one resolution)."""
        if self._last[0] != resolution:
            self._last = (resolution, shadowmap.depth_map(self.renderer.ctx, self.scene,
                                                          self.view, resolution))
        depth = self._last[1]
        share = shadowmap.shadowed(self.view, depth, self.points, bias, pcf)
        lit_map = np.zeros_like(self.compared)
        lit_map[self.compared] = share <= 0.5
        return ShadowMapError(self.image, self.compared, self.lit_exact, lit_map, resolution,
                              bias, pcf)

    def release(self) -> None:
        self.renderer.release()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()
