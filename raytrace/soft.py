"""Soft-shadow masks: per light, how many of its samples reach each pixel.

An area light is its N samples (`shadowvol.scene.hard_lights`), each a point light (sphere) or
a 90-degree spot light (rect, disk: one-sided emission); a point, spot or directional light is
the case N = 1.  Sample s reaches pixel p exactly when `raytrace.masks` would call p lit by that
sample alone: the same primary hit, the same n·l > 0 and cone test, one shadow segment with the
masks' margins.  The samples are traced through `raytrace.masks.shadow_masks` itself, a scene
per chunk of samples, so the two can never disagree.

Per-sample facing: sample s faces p when n·l_s > 0 and p is inside the sample's cone (for a
rect or disk: on the emitting side of the light's plane).  `facing` says that SOME sample of the
light faces p; it is the lit test with nothing in the way (a backend that reports no occluder).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from shadowvol.scene import Scene, hard_lights

from .masks import MaskTracer, scene_backend, shadow_masks

# Hard masks held at once: a chunk of samples is traced as one scene of this many
# (samples x pixels) booleans at most.
CHUNK_MASK_PIXELS = 1 << 25


class SoftMasks(NamedTuple):
    """The per-sample masks of a scene, reduced to counts.

    lit_count : (L, H, W) uint16, how many of light i's samples reach the pixel
    samples   : (L,) int64, N per light
    facing    : (L, H, W) bool, some sample of light i faces the pixel (see the module)
    coverage  : (H, W) bool
    """

    lit_count: np.ndarray
    samples: np.ndarray
    facing: np.ndarray
    coverage: np.ndarray

    @property
    def visibility(self) -> np.ndarray:
        """(L, H, W) float32: lit_count / N."""
        return (self.lit_count / self.samples[:, None, None]).astype(np.float32)

    @property
    def lit(self) -> np.ndarray:
        """(L, H, W) bool: every sample reaches the pixel (count == N), the hard `lit`."""
        return self.lit_count == self.samples[:, None, None]

    @property
    def umbra(self) -> np.ndarray:
        """(L, H, W) bool: facing, yet no sample reaches the pixel."""
        return self.facing & (self.lit_count == 0)

    @property
    def penumbra(self) -> np.ndarray:
        """(L, H, W) bool: some samples reach the pixel, not all (0 < count < N)."""
        return (self.lit_count > 0) & ~self.lit


class _Unoccluded:
    """A backend that finds the same primary hits as `tracer` but no occluder: the masks of
    a scene traced through it are the facing (and cone) tests alone."""

    def __init__(self, tracer):
        self._tracer = tracer

    def __getattr__(self, name):
        return getattr(self._tracer, name)

    def occluded(self, origins, directions, tmax, parallel=True):
        return np.zeros(len(origins), bool)

    def occluded_leaving(self, origins, directions, tmax, own):
        return np.zeros(len(origins), bool)


def sample_masks(scene: Scene, light_index: int, backend: str | MaskTracer = "embree",
                 facing: bool = False):
    """Yield (first, lit) over chunks of light `light_index`'s samples: lit (n, H, W) bool,
    the hard masks of samples first .. first + n - 1 (`facing=True`: of the facing test)."""
    mt = scene_backend(scene, backend) if isinstance(backend, str) else backend
    if facing:
        mt = MaskTracer(_Unoccluded(mt.tracer), mt.triangles, mt.origin)
    hard = hard_lights(scene.lights[light_index])
    chunk = max(1, CHUNK_MASK_PIXELS // (scene.width * scene.height))
    for first in range(0, len(hard), chunk):
        lit, _ = shadow_masks(scene.replace(lights=hard[first:first + chunk]), mt)
        yield first, lit


def soft_masks(scene: Scene, backend: str | MaskTracer = "embree") -> SoftMasks:
    """The per-sample counts of every light of `scene` (see `SoftMasks`).

    backend : "embree", "numpy", or `raytrace.masks.scene_backend(scene, ...)` built once."""
    mt = scene_backend(scene, backend) if isinstance(backend, str) else backend
    count, coverage = lit_counts(scene, mt)
    facing = np.zeros(count.shape, bool)
    for i in range(len(scene.lights)):
        for _, lit in sample_masks(scene, i, mt, facing=True):
            facing[i] |= lit.any(axis=0)
    return SoftMasks(count, sample_counts(scene), facing, coverage)


def sample_counts(scene: Scene) -> np.ndarray:
    """(L,) int64: N of every light (1 for point, spot and directional lights)."""
    return np.array([len(hard_lights(lt)) for lt in scene.lights], np.int64)


def lit_counts(scene: Scene, backend: str | MaskTracer = "embree"
               ) -> tuple[np.ndarray, np.ndarray]:
    """`SoftMasks.lit_count` (L, H, W) uint16 and coverage (H, W) bool alone."""
    mt = scene_backend(scene, backend) if isinstance(backend, str) else backend
    count = np.zeros((len(scene.lights), scene.height, scene.width), np.uint16)
    for i in range(len(scene.lights)):
        for _, lit in sample_masks(scene, i, mt):
            count[i] += lit.sum(axis=0, dtype=np.uint16)
    _, coverage = shadow_masks(scene.replace(lights=()), mt)
    return count, coverage
