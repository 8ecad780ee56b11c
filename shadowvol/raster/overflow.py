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

from shadowvol.errors import RenderError
from shadowvol.raster import methods, stencil
from shadowvol.raster.passes import count_volumes
from shadowvol.raster.topology import Topology
from shadowvol.scene import hard_lights

STENCIL_LIMIT = 256  # counts are taken modulo this
SATURATED = 255
# An edge counts as convex when the neighbouring corner lies no more than this far (relative:
# the sine of the angle) on the outer side of the triangle's plane: coplanar neighbours (a box's
# faces, after a rotation) differ from 0 by rounding only.
CONVEX_TOLERANCE = 1e-9


class StencilOverflowError(RenderError):
    """The stencil count may have wrapped to 0 at pixels the frame calls lit.

    light : int, index of the light;  pixels : (H, W) bool, where (row 0 at the top)."""

    def __init__(self, light: int, pixels: np.ndarray):
        self.light, self.pixels = light, pixels
        super().__init__(
            f"stencil overflow: light {light} may be behind {STENCIL_LIMIT} or more layers "
            f"of geometry at {int(pixels.sum())} pixels drawn as lit (the 8-bit stencil "
            f"counts modulo {STENCIL_LIMIT}); fewer stacked layers between the surfaces and "
            f"the light avoid it")


def is_closed_convex(topo: Topology) -> bool:
    """True when the welded mesh bounds one convex body, so that a segment crosses it at most
    twice.  Tested in numpy on its topology:

    - closed and consistently wound: every edge has exactly two triangles, running it in
      opposite directions, and no triangle is degenerate;
    - locally convex: at every edge, the second triangle's opposite corner lies on the inner
      side of the first triangle's plane (or on it, up to a relative CONVEX_TOLERANCE), for one
      orientation of the whole mesh;
    - Euler characteristic V − E + F = 2.  A closed surface that is locally convex everywhere
      has only sphere-like components (each of characteristic 2), so 2 means one component,
      and a connected, closed, locally convex surface bounds a convex body."""
    faces = topo.faces
    if len(faces) < 4 or np.any(topo.triangles_per_edge != 2):
        return False
    winding = np.bincount(topo.inc_edge, weights=topo.inc_parity, minlength=len(topo.edges))
    if np.any(winding != 0):
        return False
    if len(topo.vertices) - len(topo.edges) + len(faces) != 2:
        return False
    normals, origins = topo.face_frames
    # incidences are sorted by edge, two per edge: pair each edge's first triangle with the
    # second triangle's opposite corner
    first, corner = topo.inc_face[0::2], topo.vertices[topo.inc_opposite[1::2]]
    n, towards = normals[first], corner - origins[first]
    scale = np.linalg.norm(n, axis=1) * np.linalg.norm(towards, axis=1)
    if np.any(scale == 0):
        return False
    side = np.einsum("ij,ij->i", n, towards) / scale
    return bool(np.all(side <= CONVEX_TOLERANCE) or np.all(side >= -CONVEX_TOLERANCE))


def topology_bound(topo: Topology) -> int:
    """At most how many of these triangles one segment can cross: 2 for a closed convex mesh,
    else the number of triangles."""
    return 2 if is_closed_convex(topo) else len(topo.faces)


def object_bound(vertices: np.ndarray, faces: np.ndarray) -> int:
    """`topology_bound` of a mesh: vertices (n, 3) float64, faces (m, 3) int."""
    return topology_bound(Topology.build(vertices, faces))


def count_bound(topologies) -> int:
    """A bound on the stencil count at any pixel for any light of a scene whose objects have
    these topologies (see the module)."""
    return sum(topology_bound(t) for t in topologies)


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

    count_volumes(ctx, gl, target, volumes, zfail, halve=halve, clip_planes=clip_planes,
                  counting=lambda zfail_group, depth_clamp: stencil.entering_faces_counting(
                      gl, zfail=zfail_group, depth_clamp=depth_clamp))
    entering = target.read_stencil().astype(np.int16) & 0xFF  # read as signed; want 0..255
    return (entering >= SATURATED) & lit


def check_frame(renderer, result, silhouettes: str, camera, lights, halve: bool) -> None:
    """Raise StencilOverflowError where a light's count may have wrapped to 0 at a pixel
    `renderer`'s frame `result` drew lit: a saturating pass per light counts the faces by
    which view rays enter volumes (`find_wrapped`), and a pixel found there is cleared by any
    other valid counting (z-fail; z-pass where the near plane cuts no volume) that stays below
    255."""
    camera = renderer.scene.camera if camera is None else camera
    vols = renderer.volumes(silhouettes)
    clip = methods.zpass_clip_planes(renderer.geometry.bounds, camera, renderer.scene.aspect,
                                     renderer.geometry.extent)
    lights = renderer.scene.lights if lights is None else lights
    # an area light's samples are checked one by one against every pixel any sample lit (a
    # superset of the sample's own lit pixels: it may raise where it need not, never the other
    # way); the casters its samples counted with z-fail stay z-fail (valid)
    for i, light in ((i, hard) for i, lt in enumerate(lights) for hard in hard_lights(lt)):
        light4 = light.homogeneous
        if vols.light4 is None or not np.array_equal(vols.light4, light4):
            vols.prepare(light4)  # (the frame's last light is still prepared)
        choice = result.zfail[i]
        drawn = result.lit_count[i] > 0
        wrapped = find_wrapped(renderer.ctx, renderer.gl, renderer.target, vols, choice,
                               drawn, clip, halve)
        # a pixel is cleared by any valid counting whose entering faces stay below 255
        zpass_valid = not methods.needs_zfail(renderer.geometry.bounds, camera,
                                              renderer.scene.aspect, light4,
                                              renderer.geometry.extent).any()
        others = [np.ones_like(choice)] + ([np.zeros_like(choice)] if zpass_valid else [])
        for other in others:
            if not wrapped.any():
                break
            if not np.array_equal(other, choice):
                wrapped &= find_wrapped(renderer.ctx, renderer.gl, renderer.target, vols,
                                        other, drawn, clip)
        if wrapped.any():
            raise StencilOverflowError(i, wrapped)
