"""raytrace: the reference Whitted ray tracer and the reference shadow masks.

    import raytrace
    image = raytrace.render(scene)                # (H, W, 3) float64 linear RGB
    lit, coverage = raytrace.shadow_masks(scene)  # (L, H, W) bool, (H, W) bool
    soft = raytrace.soft_masks(scene)             # per-sample counts of area lights
    truth = raytrace.ground_truth(scene)          # + depth, normal, object_id, facing, casters

It shares with the rasterizer only the scene model and the frame (`shadowvol.frame`), the
writers (`shadowvol.io`, `shadowvol.pictures`), the errors and their exit statuses
(`shadowvol.errors`) and docs/CONVENTIONS.md, never its code, so that it stays an independent
witness.  The witness is this package's top (masks, groundtruth, soft, backends, intersect,
tolerances, camera); global illumination, Whitted's `render` among it, is `raytrace.outlook`,
which the witness never imports.  It never imports GL, and holds no command: its command line
is `shadowvol.cli.raytrace`.
"""

from __future__ import annotations

import importlib

__all__ = ["GroundTruth", "ground_truth", "render", "shadow_masks", "soft_masks"]

# name -> the module that defines it, imported on first access (PEP 562): `import raytrace`
# (and `python -m raytrace`, before its command line takes Ctrl-C) loads nothing but itself
_LAZY = {"GroundTruth": "raytrace.groundtruth", "ground_truth": "raytrace.groundtruth",
         "render": "raytrace.outlook.whitted", "soft_masks": "raytrace.soft"}


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'raytrace' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))


def shadow_masks(scene, backend="embree"):
    """Reference masks per docs/CONVENTIONS.md: lit (L, H, W) bool, coverage (H, W) bool.
    An area light's `lit` is "every sample reaches the pixel" (`raytrace.soft`); see
    `raytrace.masks.shadow_masks` for the hard lights."""
    from raytrace.masks import shadow_masks as hard_shadow_masks
    from raytrace.soft import lit_counts, sample_counts
    from shadowvol.scene import AreaLight

    if any(isinstance(light, AreaLight) for light in scene.lights):
        count, coverage = lit_counts(scene, backend)
        return count == sample_counts(scene)[:, None, None], coverage
    return hard_shadow_masks(scene, backend=backend)
