"""The 8-bit stencil: detecting a count that wrapped to 0.

The stencil counts volumes with INCR_WRAP / DECR_WRAP in 8 bits, so a pixel inside 256 volumes
(or 512, ...) reads 0: lit, wrongly.  Every triangle casts (two-sided surfaces), and a point is
inside one volume per triangle crossed by its segment to the light, so this needs 256 layers of
geometry between one visible point and one light.

Detection, in two steps:

1. A conservative CPU bound per scene, computed once (`count_bound`): the count at a pixel is at
   most the number of triangles a segment can cross, at most 2 for a closed convex object (a
   box, an icosphere) and at most the triangle count for anything else; summed over objects.
   Below 256 the count cannot wrap and nothing more is done: the normal frame is unchanged.
2. Otherwise, after the frame, per light, one more volume pass (`find_wrapped`) counts only the
   faces by which the view ray ENTERS a volume, saturating at 255 (`stencil.
   entering_faces_counting`).  The true count never exceeds it, so a pixel can have wrapped
   only where it saturated.  A saturated pixel in shadow is right (its count is not 0 mod 256,
   so not 0).  A saturated pixel the frame calls lit is ambiguous (a count of 0 or of 256k):
   the check is repeated counting the other way along the view ray (z-fail: from the surface
   to infinity, always valid; z-pass: from the eye, when no volume reaches the near plane),
   which bounds the same true count; a pixel either count keeps below 255 is cleared.  Pixels
   ambiguous both ways raise `StencilOverflowError`, naming the light and the pixels.

The check is not a correction: it turns a silently wrong shadow into a clear error (exit status
3 from the command line).  Scenes that meet it: more than ~255 stacked sheets or ~128 stacked
closed objects between a visible point and a light.
"""

from __future__ import annotations

import numpy as np

from . import stencil

STENCIL_LIMIT = 256  # counts are taken modulo this
SATURATED = 255
# Objects with more triangles are not tested for convexity (their bound is their triangle
# count, over the limit anyway); the test costs ~1 ms per 1000 triangles, once per scene.
CONVEXITY_TEST_MAX = 20000


class StencilOverflowError(RuntimeError):
    """The stencil count may have wrapped to 0 at pixels the frame calls lit.

    light : int, index of the light;  pixels : (H, W) bool, where (row 0 at the top)."""

    def __init__(self, light: int, pixels: np.ndarray):
        self.light, self.pixels = light, pixels
        super().__init__(
            f"stencil overflow: light {light} may be behind {STENCIL_LIMIT} or more layers "
            f"of geometry at {int(pixels.sum())} pixels drawn as lit (the 8-bit stencil "
            f"counts modulo {STENCIL_LIMIT}); fewer stacked layers between the surfaces and "
            f"the light avoid it")


def object_bound(vertices: np.ndarray, faces: np.ndarray) -> int:
    """At most how many of these triangles one segment can cross: 2 for a closed convex mesh,
    else the number of triangles.  vertices (n, 3) float64, faces (m, 3) int."""
    import trimesh

    if len(faces) <= 2 or len(faces) > CONVEXITY_TEST_MAX:
        return len(faces)
    mesh = trimesh.Trimesh(vertices, faces, process=True)  # welds duplicated seam vertices
    if mesh.is_watertight and mesh.is_convex:
        return 2
    return len(faces)


def count_bound(scene) -> int:
    """A bound on the stencil count at any pixel for any light of `scene` (see the module)."""
    return sum(object_bound(o.vertices, o.faces) for o in scene.objects)


def find_wrapped(ctx, gl, target, volumes, zfail: np.ndarray, lit: np.ndarray,
                 clip_planes: np.ndarray | None = None, halve: bool = False) -> np.ndarray:
    """(H, W) bool: pixels where the count of the light `volumes` was prepared for may have
    wrapped although the frame drew them lit (`lit` (H, W) bool, row 0 at the top).
    zfail : (n_objects,) bool, the method per caster, as in the count pass.  clip_planes : the
    z-pass clip box (`methods.zpass_clip_planes`), as the count pass uses it: the counts at
    covered pixels, the only ones read here, are the same, at a fraction of the fill.  halve:
    as the count pass did (`CpuVolumes.draw_sides`): the frame's count is then half as large
    for those casters, and so is the entering count that bounds it.  Leaves the stencil
    holding the saturated entering counts."""
    from .passes import count_volumes

    count_volumes(ctx, gl, target, volumes, zfail, halve=halve, clip_planes=clip_planes,
                  counting=lambda zfail_group, depth_clamp: stencil.entering_faces_counting(
                      gl, zfail=zfail_group, depth_clamp=depth_clamp))
    entering = target.read_stencil().astype(np.int16) & 0xFF  # read as signed; want 0..255
    return (entering >= SATURATED) & lit
