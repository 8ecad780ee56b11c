"""Every tolerance of the ray tracer, named, in one place (as trimesh's `tol` and PBRT's
`ShadowEpsilon`).  Nothing else in `raytrace/` writes a bare epsilon.

Why the offsets are what they are
---------------------------------
A secondary ray (shadow, reflection, refraction) starts on a surface.  Rounding puts its origin a
little above or below that surface, and then it can hit the very surface it leaves ("shadow
acne").  We never rely on a `t_min` for that — Embree's wrapper always starts rays at t = 0 — but
move the origin off the surface along the geometric normal, to the side the ray leaves on.

The offset must beat the worst rounding of any backend.  Embree works in float32 (vertices,
origins, directions and t are all converted to float32: 24-bit mantissa, relative spacing
2**-23 ~ 1.2e-7).  A coordinate of magnitude M is therefore off by up to ~6e-8 * M, and so is
a float32 vertex.  The offset is `SURFACE_OFFSET_RELATIVE` times the scene's length scale
`max(scene.extent, largest |coordinate|)`: the extent because that is the size of the features,
the largest coordinate because float32 resolution depends on the magnitude of coordinates, not
on the scene's size (a small scene far from the origin needs a larger offset).  1e-4 of that is
~800 float32 ulps, ample, yet a tenth of a pixel's footprint in a 1000-pixel-wide view of the
scene, so contact shadows stay put.  The numpy backend (float64) would manage with far less,
but both backends use the same offset so they trace the same rays.

Where float32 is used: everything Embree touches (see `raytrace.backends`), and all of the
masks' arithmetic (`raytrace.masks`: the rays, hit points and shadow-ray starts), which is as
precise as Embree's own and ~1e-3 of the offset.  The intersection formulas, the numpy backend
and the Whitted renderer are float64.
"""

from __future__ import annotations

import numpy as np

# Secondary rays start this far (relative to `length_scale`) off the surface, along the normal.
SURFACE_OFFSET_RELATIVE = 1e-4

# Hits at lambda <= T_MIN are behind (or at) the ray origin and do not count.  Zero: the
# offset above, not a minimum distance, keeps rays off the surface they leave.
T_MIN = 0.0

# The numpy BVH pads each node's box by this much (relative to the largest |coordinate| of its
# triangles) so that rounding in the slab test never culls a ray that touches a triangle on the
# box's face.
BVH_BOX_PAD_RELATIVE = 1e-9

# Backend agreement (tests/test_backends.py): numpy (float64) and Embree (float32) may pick
# different triangles only for rays that pass within this distance (relative to the length
# scale) of a triangle edge: there float32 rounding decides which of the two triangles is hit.
# float32 puts a coordinate within ~6e-8 (relative) of its value and Embree's edge tests add a
# few ulps more; 1e-5 is ~100 times that.
EDGE_AGREEMENT_RELATIVE = 1e-5


def length_scale(scene) -> float:
    """The scene's length scale for tolerances: max(scene.extent, largest |coordinate| of any
    vertex or of the eye).  float64 > 0."""
    biggest = max(float(np.abs(o.vertices).max()) for o in scene.objects)
    return max(scene.extent, biggest, float(np.abs(scene.camera.eye).max()))


def surface_offset(scene) -> float:
    """How far secondary rays start off the surface they leave (world units)."""
    return SURFACE_OFFSET_RELATIVE * length_scale(scene)
