"""raytrace: the reference Whitted ray tracer and the reference shadow masks.

    import raytrace
    image = raytrace.render(scene)                # (H, W, 3) float64 linear RGB
    lit, coverage = raytrace.shadow_masks(scene)  # (L, H, W) bool, (H, W) bool
    soft = raytrace.soft_masks(scene)             # per-sample counts of area lights

It shares only the scene model (`shadowvol.scene`) and CONVENTIONS.md with the rasterizer, never
its code, so that it stays an independent witness.  It never imports GL.
"""

from __future__ import annotations

__all__ = ["render", "shadow_masks", "soft_masks"]


def render(scene, max_depth=None, backend="embree", progress=None):
    """Whitted-ray-trace `scene`: (H, W, 3) float64 linear RGB, row 0 at the top.
    See `raytrace.whitted.render`."""
    from .whitted import render as _render
    return _render(scene, max_depth=max_depth, backend=backend, progress=progress)


def shadow_masks(scene, backend="embree"):
    """Reference masks per CONVENTIONS.md: lit (L, H, W) bool, coverage (H, W) bool.
    An area light's `lit` is "every sample reaches the pixel" (`raytrace.soft`).
    See `raytrace.masks.shadow_masks`."""
    from shadowvol.scene import AreaLight

    if any(isinstance(light, AreaLight) for light in scene.lights):
        from .soft import lit_counts, sample_counts
        count, coverage = lit_counts(scene, backend)
        return count == sample_counts(scene)[:, None, None], coverage
    from .masks import shadow_masks as _shadow_masks
    return _shadow_masks(scene, backend=backend)


def soft_masks(scene, backend="embree"):
    """Per-sample counts of every light: `raytrace.soft.SoftMasks` (lit_count (L, H, W)
    uint16, visibility, lit, umbra, penumbra, facing, coverage)."""
    from .soft import soft_masks as _soft_masks
    return _soft_masks(scene, backend=backend)
