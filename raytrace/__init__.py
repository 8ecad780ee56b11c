"""raytrace: the reference Whitted ray tracer and the reference shadow masks.

    import raytrace
    image = raytrace.render(scene)                # (H, W, 3) float64 linear RGB
    lit, coverage = raytrace.shadow_masks(scene)  # (L, H, W) bool, (H, W) bool
    truth = raytrace.ground_truth(scene)          # + depth, normal, object_id, facing, casters

It shares with the rasterizer only the scene model, the writers (`shadowvol.io`,
`shadowvol.pictures`), the exit-status table (`shadowvol.cli.status`) and docs/CONVENTIONS.md,
never its code, so that it stays an independent witness.  It never imports GL.
"""

from __future__ import annotations

from raytrace.groundtruth import GroundTruth, ground_truth
from raytrace.masks import shadow_masks
from raytrace.whitted import render

__all__ = ["GroundTruth", "ground_truth", "render", "shadow_masks"]
