"""Every tolerance of the ray tracer, named, in one place (as trimesh's `tol` and PBRT's
`ShadowEpsilon`).  Nothing else in `raytrace/` writes a bare epsilon.

The reference masks: the exact segment, shortened only by float error bounds
---------------------------------------------------------------------------
CONVENTIONS.md defines lit as "nothing lies between the surface point p and the light".  The
masks test exactly that segment, p to the light (or the ray from p toward a directional light),
on its own line: a shadow ray never leaves that line.  What may be dropped is only what float
arithmetic cannot tell apart from the segment's end points (as PBRT-v3 §3.9 and Wächter &
Binder, Ray Tracing Gems ch. 6, bound the error of a hit point instead of guessing an epsilon):

1. **The local frame.**  Embree is float32.  Its triangles and rays are the scene's float64
   coordinates minus one float64 origin, the camera's eye (`frame_origin`), subtracted before
   rounding: every error below is relative to coordinates measured from the eye, so a scene
   translated by 1e6 is traced as exactly as at the origin, and the error at a visible point
   grows with its distance from the eye (as its pixel's footprint does), not with where the
   world's origin happens to lie.
2. **The hit triangle is excluded by id, not by distance.**  A segment that starts on a plane
   meets it nowhere else, so the visible triangle k never blocks its own point's segment:
   whatever Embree reports for triangle k is rounding.  The height bound below covers k's
   own float32 arithmetic for a well-shaped triangle; for a sliver (`is_sliver`: smallest
   angle below ~14.5 degrees, where the float32 normal's error grows as 1/sin of that angle)
   it does not, so a shadow ray leaving a sliver that Embree finds blocked is cast again
   (`first_hit`) to see whether the blocker is k; if it is, the ray goes on from there
   (`OWN_HIT_RETRIES`).  Only slivers: a second cast of every blocked ray would cost the
   masks much of their speed (slivers are 0.1% of the bunny's triangles).
3. **At p, a height bound of the float error of p relative to its own plane.**  Other
   triangles through p (a coplanar decal, the other half of a quad) must not count either, and
   they are told apart from blockers only up to float error.  p is computed in float64 on
   triangle k's float64 plane (the exact pixel ray cut with it), so its float64 error is
   negligible; what moves it relative to a plane through it, measured along that plane's unit
   normal n, is all float32 and all bounded by spacings of the coordinates weighted by |n|:
   rounding p to float32 (<= 1/2 spacing per component: <= 2**-24 · Σ|n_j||p_j|), adding the
   offset along the ray (the same again), rounding the corners (<= 2**-24 · W, with
   W = Σ_j |n_j| max_i |v_ij|, the weight of the corners' coordinates), Embree's v − origin and
   the dot product with its normal (a few 2**-24 · (W + Σ|n_j||p_j|)).  In all about 4 units of
   2**-23 · (W + Σ|n_j||p_j|): `shadow_height` takes `SURFACE_ERROR_ULPS` = 8 of them, twice
   the sum, and the segment starts at that height above the plane, on its own line
   (t = height / (n·l)).  Weighting by |n_j| is what keeps a horizontal ground quad 1e7 wide
   exact: its corners' x and z are large but its plane depends only on y, and W is the eye's
   height above it.
3b. **The lift is never longer than `LIFT_HEIGHTS` heights.**  Along a unit l the lift is
   height / (n·l̂): at n·l̂ = 1e-3 a thousand heights, and a real occluder of the same mesh
   a little way along (a bunny's fold under a low spot light) would be skipped.  So where
   n·l̂ < 1 / LIFT_HEIGHTS the skipped piece, p to the lifted start, is traced again in
   float64 from p itself (`TriangleBackend.occluded_leaving`), counting every triangle except
   p's own and those whose float64 plane passes through p up to its float64 error
   (`plane_error64`: the same weights in spacings of 2**-52).  Those are the only triangles
   that may be met there by rounding alone: a plane through p meets the segment's line at p
   only (or contains it), so in exact arithmetic they never block.  Anything else the float64
   walk meets is a blocker, however grazing the light.  What the masks lose at the surface is
   therefore geometry within LIFT_HEIGHTS heights of p along the ray (a contact shadow
   thinner than ~3e-5 of the distance to the eye), at every angle.  The Embree backend runs
   that float64 test only on the triangles whose boxes the piece's box touches
   (`raytrace.neargrid`), each box padded by a bound of where the test can report a hit:
   the error of λ (off the plane) and of the barycentric coordinates (in it) is a few tens of
   spacings of 2**-52 of the reach R (a bound of |x| of every corner and of p) divided by
   sin² of the triangle's angle at its first corner; `NEAR_BOX_ERROR_ULPS` takes 1024 of
   them, and a triangle with sin² below `NEAR_SLIVER_SIN2` (where that bound no longer holds
   by itself) is tested with every piece.
4. **At a point light, a bound of the light position's own error.**  The segment ends
   `light_margin` before the light: 8 spacings of the light's coordinates, of the segment's
   length (Embree's t is relative to it) and, if some triangle's plane passes through the light
   up to its own float32 error (a light lying on a floor), of that triangle's weight W, so that
   a surface through the light casts no shadow (its shadow volume has no thickness in the
   rasterizer either) -- and nothing else near the light is dropped: a card 1e-5 beside a light
   one unit from the eye still shadows (the margin is ~1e-6).

Geometry that lies within LIFT_HEIGHTS heights of p along the segment, or that close to the
light, does not count: a contact shadow thinner than ~3e-5 of the distance to the eye is lost,
nothing else (`tests/raytrace/test_margins_property.py` checks this against a float64 walk of
the segment at n·l̂ down to 1e-4 and 1e5 from the origin).
`tests/raytrace/test_reference_exact.py` measures the masks against a float64 brute-force segment test
on large translations, huge ground quads, cards beside lights and grazing creases, and checks
the height bound directly (rays leaving random triangles at down to 1e-6 rad of grazing never
hit a coplanar copy of the triangle).

Why not the old ways.  A start at p + offset·n (offset 1e-4 of the scene size) moves the ray
OFF the segment's line: under grazing light a shadow edge moves by offset / tan(elevation), and
in concave creases the moved start escapes the neighbouring triangle that really blocks the
segment.  A margin of 64 spacings of the hit triangle's largest world coordinate (the next
version) grows with the distance from the world's origin: 5 cm kerbs under a low sun lost their
shadows once the scene was translated by 1e4, and a light margin of the whole scene's largest
coordinate let a lamp shade on a 1e6-wide ground quad leak light (3.8 units of margin).

The Whitted images keep their own offset -----------------------------------------
`raytrace.outlook.whitted` (images, reflection and refraction rays, whose start points must lie off
the surface on a given side) still starts secondary rays at p + `surface_offset`·n, 1e-4 of the
scene's length scale, as before: the images are not compared pixel by pixel, and reflected and
refracted rays have no segment to stay on.

Where float32 is used: everything Embree touches (see `raytrace.backends`) and, in the masks,
the primary rays (only to choose the visible triangle) and the shadow rays, all in the eye's
frame.  The hit point is computed in float64 and rounded to float32 once; n·l (which decides
"facing") and the margins are float64; the shadow ray's start, p + margin·l, is added in
float32 (counted in the bound above); its tfar is rounded down, never up; the pieces a long
lift skips (item 3b) are float64 from end to end.  The intersection
formulas, the numpy backend and the Whitted renderer are float64.
"""

from __future__ import annotations

import numpy as np

from shadowvol import cameras

# float32's relative spacing: the distance from 1.0 to the next float32.
FLOAT32_EPS = float(np.finfo(np.float32).eps)  # 2**-23
FLOAT64_EPS = float(np.finfo(np.float64).eps)  # 2**-52

# The masks' margins (see above), in float32 spacings (2**-23 relative) of |n|-weighted
# coordinates in the eye's frame: at the surface (about 4 are accounted for), and before a point
# light.
SURFACE_ERROR_ULPS = 8.0
LIGHT_ERROR_ULPS = 8.0

# The longest lift along the segment, in heights (item 3b): where the lift would be longer
# (n·l̂ < 1 / LIFT_HEIGHTS) the piece it skips is traced in float64.
LIFT_HEIGHTS = 16.0

# The float64 near pieces' candidates (item 3b, `raytrace.neargrid`): a triangle's box is
# padded by NEAR_BOX_ERROR_ULPS spacings of 2**-52 of the reach over sin² of its angle at its
# first corner; below NEAR_SLIVER_SIN2 (sin ~1e-5) every piece tests it.
NEAR_BOX_ERROR_ULPS = 1024.0
NEAR_SLIVER_SIN2 = 1e-10

# A triangle whose smallest angle has a sine below 1 / SLIVER_SHAPE (~14.5 degrees) is a
# sliver: the float32 error of its normal, relative, grows as 1 / sin(smallest angle), which
# the height bound's 2x allowance does not cover; its shadow rays are checked by id instead.
SLIVER_SHAPE = 4.0

# How many times a shadow ray that Embree finds blocked by the very triangle it leaves is cast
# on from that hit before the triangle is taken as not blocking (it cannot: see above).
OWN_HIT_RETRIES = 3

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

# Backend agreement (tests/raytrace/test_backends.py): numpy (float64) and Embree (float32) may pick
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


def frame_origin(scene) -> np.ndarray:
    """The origin of the masks' float32 frame: the camera's eye, (3,) float64 -- the
    rasterizer's frame too (`shadowvol.cameras.frame_origin`, the one definition)."""
    return cameras.frame_origin(scene.camera)


def error_weight(normals: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """W = Σ_j |n_j| · max_i |corner_ij| per triangle: the size of the float32 rounding of its
    plane, in spacings.  normals : (M, 3) unit;  corners : (M, 3, 3), in the eye's frame.
    Returns (M,) float64."""
    biggest = np.maximum(np.maximum(np.abs(corners[:, 0]), np.abs(corners[:, 1])),
                         np.abs(corners[:, 2]))  # = np.abs(corners).max(axis=1), faster
    return np.einsum("mj,mj->m", np.abs(normals), biggest)


def is_sliver(corners: np.ndarray) -> np.ndarray:
    """(M,) bool: the triangles corners (M, 3, 3) whose smallest angle is below
    asin(1 / SLIVER_SHAPE), or that are degenerate."""
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    e1, e2 = b - a, c - a
    return sliver_edges(e1, e2, c - b, norm_rows(cross_rows(e1, e2)))


def sliver_edges(e1: np.ndarray, e2: np.ndarray, e3: np.ndarray, area2: np.ndarray
                 ) -> np.ndarray:
    """`is_sliver` from the edges b − a, c − a, c − b (M, 3) and |e1 × e2| (M,)."""
    l1, l2, l3 = (norm_rows(e) for e in (e1, e2, e3))
    # the two longest edges' product: rounding is monotone, so it is the largest product
    longest = np.maximum(np.maximum(l1 * l2, l1 * l3), l2 * l3)
    return longest >= SLIVER_SHAPE * area2


def cross_rows(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """u × v of rows (M, 3): np.cross's products and differences, without its copies."""
    out = np.empty(np.broadcast_shapes(u.shape, v.shape))
    out[:, 0] = u[:, 1] * v[:, 2] - u[:, 2] * v[:, 1]
    out[:, 1] = u[:, 2] * v[:, 0] - u[:, 0] * v[:, 2]
    out[:, 2] = u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]
    return out


def norm_rows(u: np.ndarray) -> np.ndarray:
    """|u| of rows (M, 3), summed in np.linalg.norm's order."""
    return np.sqrt(u[:, 0] * u[:, 0] + u[:, 1] * u[:, 1] + u[:, 2] * u[:, 2])


def shadow_height(weight):
    """The masks' margin at the surface: the height above the hit triangle's plane below which
    geometry does not count.  weight : float or (n,) float64, W + Σ_j |n_j||p_j| (the
    triangle's `error_weight` plus p's coordinates weighted by |n|, eye's frame).  Never 0: a
    weight of 0 still gets the spacing at the smallest normal float32 scale, 1e-30."""
    return SURFACE_ERROR_ULPS * FLOAT32_EPS * np.maximum(weight, 1e-30)


def plane_error64(weight):
    """The float64 twin of `shadow_height`: how far (world units) a plane through p may pass
    from p by float64 rounding alone.  weight : float or array, W + Σ_j |n_j||p_j| (eye's
    frame)."""
    return SURFACE_ERROR_ULPS * FLOAT64_EPS * np.maximum(weight, 1e-300)


def light_margin(light_position, length, through_weight: float = 0.0):
    """The masks' margin at a point light: the distance before the light (world units) within
    which geometry does not count.  light_position : (3,) in the eye's frame; length : float or
    (n,), the segments' lengths; through_weight : the largest weight W + Σ|n_j||L_j| of the
    triangles whose planes pass through the light up to their float32 error (`through_light`),
    0 if none."""
    own = float(np.abs(light_position).max())
    return LIGHT_ERROR_ULPS * FLOAT32_EPS * np.maximum(own + np.asarray(length) +
                                                       through_weight, 1e-30)


def through_light(normals: np.ndarray, plane_d: np.ndarray, weight: np.ndarray,
                  light_position: np.ndarray) -> float:
    """The largest weight W + Σ|n_j||L_j| of the triangles whose plane passes within its own
    `shadow_height` of the light (a floor the light lies on), 0.0 if none.  normals (M, 3),
    plane_d (M,), weight (M,): eye's frame; light_position (3,)."""
    a, at = np.abs(normals), np.abs(light_position)
    # dot products summed x, y, z left to right, as `raytrace.maskkernels.through_light` does
    w = weight + (a[:, 0] * at[0] + a[:, 1] * at[1] + a[:, 2] * at[2])
    n, p = normals, light_position
    near = np.abs((n[:, 0] * p[0] + n[:, 1] * p[1] + n[:, 2] * p[2]) - plane_d) <= \
        shadow_height(w)
    return float(w[near].max()) if near.any() else 0.0
