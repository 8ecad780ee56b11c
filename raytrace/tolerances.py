"""Every tolerance of the ray tracer, named, in one place (as trimesh's `tol` and PBRT's
`ShadowEpsilon`).  Nothing else in `raytrace/` writes a bare epsilon.

The reference masks: the exact segment, shortened only at its ends
--------------------------------------------------------------------
CONVENTIONS.md defines lit as "nothing lies between the surface point p and the light".  The
masks test exactly that segment, p to the light (or the ray from p toward a directional light),
on its own line: a shadow ray never leaves that line.  Only its two END POINTS are pulled in, so
that the surfaces that merely touch it there (the visible triangle at p, a surface through the
light) are not counted:

* at p, by a margin ALONG THE RAY of  eps / (n·l̂), which is the point of the segment at height
  `eps` above the plane of p's triangle (n the unit normal facing the light side, l̂ the unit
  direction toward the light).  Geometry lying within height `eps` of that plane near p is
  therefore not counted: a contact shadow thinner than `eps` is lost, nothing else.
* at a point light, by `light_margin` along the ray (the same number of float32 spacings, at
  the larger of the light's and the scene's coordinates).

`eps` is `SHADOW_HEIGHT_ULPS` float32 spacings at the magnitude of the hit triangle's own
coordinates, `max |coordinate|` of its three corners (which bounds p's too).  Why float32 and
why this magnitude: Embree rounds the ray origin and the triangle's vertices to float32, each
moving the triangle's plane relative to the origin by at most ~0.9 spacing of the largest
coordinate involved (half a spacing per component, times |n|_1 <= sqrt 3), and its
intersection arithmetic works on v0 − origin and edge vectors no longer than the triangle,
whose length is at most 2·sqrt(3) times that magnitude: a few spacings more.  2**-23·M·64
leaves a margin of ten or more over the sum; tests/test_reference_exact.py checks it (rays
leaving random triangles at down to 1e-6 rad of grazing never hit them; a coplanar second
triangle never shadows) and measures the masks against a float64 brute-force segment test.

Why not the old way (start at p + offset·n, offset 1e-4 of the scene size): it moves the ray
OFF the segment's line.  Under grazing light a shadow edge moves by offset / tan(elevation)
(248 interior mismatches on a wall lit at 2 degrees), and in concave creases the moved start
escapes the neighbouring triangle that really blocks the segment (5–35 interior mismatches per
light on the bunny, Suzanne and Spot at 640x480).  Moving along the ray instead keeps the line,
and the margin shrinks from 1e-4 of the scene to ~1e-5 of the coordinates' float32 resolution.

The surface point p itself is computed in float64 on the hit triangle's plane (the plane of the
triangle Embree picked, intersected with the exact pixel-centre ray), so the margin only has to
absorb float32 rounding of the shadow ray, not of the hit point.

The Whitted images keep their own offset
-----------------------------------------
`raytrace.whitted` (images, reflection and refraction rays, whose start points must lie off the
surface on a given side) still starts secondary rays at p + `surface_offset`·n, 1e-4 of the
scene's length scale, as before: the images are not compared pixel by pixel, and reflected and
refracted rays have no segment to stay on.

Where float32 is used: everything Embree touches (see `raytrace.backends`) and, in the masks,
the primary rays (only to choose the visible triangle) and the shadow rays.  The hit point is
computed in float64 and rounded to float32 once; n·l (which decides "facing") and the margins
are float64; the shadow ray's start, p + margin·l, is added in float32, an error of the size of
p's own rounding (one spacing), well inside the 64-spacing margin; its tfar is rounded down,
never up.  The intersection formulas, the numpy backend and the Whitted renderer are float64.
"""

from __future__ import annotations

import numpy as np

# float32's relative spacing: the distance from 1.0 to the next float32.
FLOAT32_EPS = float(np.finfo(np.float32).eps)  # 2**-23

# The masks' margins (see above): height above the hit triangle's plane, and distance before a
# point light, in float32 spacings of the coordinates involved.
SHADOW_HEIGHT_ULPS = 64.0

# Whitted's secondary rays start this far (relative to `length_scale`) off the surface, along
# the normal.
SURFACE_OFFSET_RELATIVE = 1e-4

# Hits at lambda <= T_MIN are behind (or at) the ray origin and do not count.  Zero: the
# offsets and margins above, not a minimum distance, keep rays off the surface they leave.
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
    """How far Whitted's secondary rays start off the surface they leave (world units)."""
    return SURFACE_OFFSET_RELATIVE * length_scale(scene)


def shadow_height(magnitude):
    """The masks' margin at the surface: height above the hit triangle's plane below which
    geometry does not count, for coordinates of magnitude `magnitude` (float or (n,) float64,
    max |coordinate| of the triangle's corners).  Never 0: a triangle at the origin still gets
    the spacing of the smallest normal float32 scale, 1e-30."""
    return SHADOW_HEIGHT_ULPS * FLOAT32_EPS * np.maximum(magnitude, 1e-30)


def light_margin(light_position, magnitude: float) -> float:
    """The masks' margin at a point light: the distance before the light (world units) within
    which geometry does not count, so that a surface through the light casts no shadow
    (its shadow volume has no thickness in the rasterizer either).  light_position : (3,);
    magnitude : the largest |coordinate| of the scene's vertices.  Which surface passes through
    the light is not known here, so the float32 spacing is taken at the larger of the light's
    and the whole scene's coordinates (a light at the origin on a floor whose corners lie at
    ±6 needs the spacing of 6, not of 0)."""
    return float(shadow_height(max(float(np.abs(light_position).max()), magnitude)))
