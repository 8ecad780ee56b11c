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

from shadowvol.cameras import pinhole
from shadowvol.errors import RenderError
from shadowvol.raster import methods, passes
from shadowvol.raster.volumes.topology import Topology

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


def convex_orientation(topo: Topology) -> int:
    """+1 when the welded mesh bounds one convex body (so that a segment crosses it at most
    twice) and its triangles are wound with normals pointing out of it, -1 when into it, 0 when
    it is not such a mesh.  Tested in numpy on its topology:

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
        return 0
    winding = np.bincount(topo.inc_edge, weights=topo.inc_parity, minlength=len(topo.edges))
    if np.any(winding != 0):
        return 0
    if len(topo.vertices) - len(topo.edges) + len(faces) != 2:
        return 0
    normals, origins = topo.face_frames
    # incidences are sorted by edge, two per edge: pair each edge's first triangle with the
    # second triangle's opposite corner
    first, corner = topo.inc_face[0::2], topo.vertices[topo.inc_opposite[1::2]]
    n, towards = normals[first], corner - origins[first]
    scale = np.linalg.norm(n, axis=1) * np.linalg.norm(towards, axis=1)
    if np.any(scale == 0):
        return 0
    side = np.einsum("ij,ij->i", n, towards) / scale
    # the neighbour's corner below every plane: normals point out of the body (a flat,
    # double-covered "body", every corner in every plane, is closed and convex but has no
    # outside: 0 for culling's sake would do, and it keeps its bound of 2 as -1)
    if np.all(side <= CONVEX_TOLERANCE):
        return 1 if np.any(side < -CONVEX_TOLERANCE) else -1
    return -1 if np.all(side >= -CONVEX_TOLERANCE) else 0


def is_closed_convex(topo: Topology) -> bool:
    """True when the welded mesh bounds one convex body, so that a segment crosses it at most
    twice (`convex_orientation` is not 0)."""
    return convex_orientation(topo) != 0


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


def find_wrapped(pipe, zfail: np.ndarray, lit: np.ndarray,
                 clip_planes: np.ndarray | None = None, halve: bool = False) -> np.ndarray:
    """(H, W) bool: pixels where the count of the light `pipe.volumes` was prepared for may
    have wrapped although the frame drew them lit (`lit` (H, W) bool, row 0 at the top).
    zfail : (n_objects,) bool, the method per caster, as in the count pass.  clip_planes : the
    z-pass clip box (`methods.zpass_clip_planes`), as the count pass uses it: the counts at
    covered pixels, the only ones read here, are the same, at a fraction of the fill.  halve:
    as the count pass did (`CpuVolumes.draw_sides`): the frame's count is then half as large
    for those casters, and so is the entering count that bounds it.  Leaves the stencil
    holding the saturated entering counts."""
    passes.count_entering(pipe, zfail, halve=halve, clip_planes=clip_planes)
    entering = pipe.target.read_stencil().astype(np.int16) & 0xFF  # read as signed; 0..255
    return (entering >= SATURATED) & lit


def check_frame(pipe, frame, result, only=None) -> None:
    """Raise StencilOverflowError where a light's count may have wrapped to 0 at a pixel the
    frame `frame` (a `pipeline.FrameState`, drawn with `pipe`) drew lit in `result`: a
    saturating pass per light counts the faces by which view rays enter volumes
    (`find_wrapped`), and a pixel found there is cleared by any other valid counting (z-fail;
    z-pass where the near plane cuts no volume) that stays below 255.  `only`: the (light,
    sample) indices to check (a hard light is its own sample 0); None: all."""
    only = None if only is None else set(only)
    vols, geometry, clip = pipe.volumes, pipe.geometry, frame.zpass_box
    # an area light's samples are checked one by one against every pixel any sample lit (a
    # superset of the sample's own lit pixels: it may raise where it need not, never the other
    # way); the casters its samples counted with z-fail stay z-fail (valid)
    for hard in frame.hard:
        i, light4 = hard.index, hard.light4
        if only is not None and (i, hard.sample) not in only or not hard.light.shadows:
            continue   # its `light_bound` is below STENCIL_LIMIT, or it is never counted
        if vols.light4 is None or not np.array_equal(vols.light4, light4):
            vols.prepare(light4)  # (the frame's last light is still prepared)
        choice = result.zfail[i]
        drawn = result.lit_count[i] > 0
        wrapped = find_wrapped(pipe, choice, drawn, clip, frame.plan.halve)
        # a pixel is cleared by any valid counting whose entering faces stay below 255
        zpass_valid = not methods.needs_zfail(geometry.bounds, frame.camera, frame.size, light4,
                                              geometry.extent).any()
        others = [np.ones_like(choice)] + ([np.zeros_like(choice)] if zpass_valid else [])
        for other in others:
            if not wrapped.any():
                break
            if not np.array_equal(other, choice):
                wrapped &= find_wrapped(pipe, other, drawn, clip)
        if wrapped.any():
            raise StencilOverflowError(i, wrapped)


# ---------------------------------------------------------------------------------------------
# A per-light bound: how many triangles any segment to this light can cross
# ---------------------------------------------------------------------------------------------

LIGHT_GRID = 1024        # cells per side of each cube face (point light) or of the plane
# the slack allowed for the rasterized volumes, in camera pixels at the triangle: GL snaps
# vertices to at least 4 sub-pixel bits (1/16 pixel, so at most 1/32 off; GPUs snap to 1/256),
# taken twice over; float32 rounding of the coordinates is added on top
PIXEL_SLACK = 1.0 / 16.0
FLOAT32_SLACK = 16 * np.finfo(np.float32).eps
GNOMONIC_STRETCH = 3.0   # d(u, v) / d(angle) <= 1 + u^2 + v^2 <= 3 on a cube face


def world_slack(camera, height: int, corners: np.ndarray,
                largest: float | None = None) -> np.ndarray:
    """(M,) float64: how far (world units) each triangle's rasterized volume faces may stray
    from the exact ones: PIXEL_SLACK camera pixels at its farthest corner from the eye, plus the
    float32 rounding of the scene's largest coordinate.  corners : (M, 3, 3) float64;
    `largest`: max |corners| when the caller keeps it (it does not depend on the camera)."""
    far = np.linalg.norm(corners - camera.eye, axis=-1).max(axis=1)
    if largest is None:
        largest = float(np.abs(corners).max())
    return pixel_slack(camera, height) * far + FLOAT32_SLACK * largest


def object_slack(camera, height: int, bounds: np.ndarray, largest: float) -> np.ndarray:
    """(n_objects,) float64: at least `world_slack` of every triangle of each object, from its
    box alone (n_objects, 2, 3): the distance from the eye is convex, so its largest value over
    a box is at one of the 8 corners, and every corner of the object's triangles lies in the
    box.  A per-frame test against the kept slack that costs 8 points an object instead of 3
    a triangle; the factor (1 + 1e-12) covers the rounding of the two computations."""
    pick = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    corners = np.stack([bounds[:, pick[:, 0], 0], bounds[:, pick[:, 1], 1],
                        bounds[:, pick[:, 2], 2]], axis=-1)             # (n, 8, 3)
    far = np.linalg.norm(corners - camera.eye, axis=-1).max(axis=1) * (1.0 + 1e-12)
    return pixel_slack(camera, height) * far + FLOAT32_SLACK * largest


def pixel_slack(camera, height: int) -> float:
    """PIXEL_SLACK camera pixels at unit distance from the eye, in world units (the larger
    side of a pixel: 1 / min(fx, fy))."""
    fx, fy, _, _ = pinhole(camera, 1, height)   # fx, fy of any width
    return PIXEL_SLACK / min(fx, fy)


def _binned_max(lo: np.ndarray, hi: np.ndarray, weight: np.ndarray, grid: int) -> np.ndarray:
    """(grid, grid) int64: per cell of [-1, 1]^2, the sum of `weight` over the rectangles
    [lo, hi] (n, 2) that overlap it (closed: touching counts)."""
    a = np.clip(np.floor((lo + 1.0) / 2.0 * grid), 0, grid - 1).astype(np.int64)
    b = np.clip(np.floor((hi + 1.0) / 2.0 * grid), 0, grid - 1).astype(np.int64) + 1
    diff = np.zeros((grid + 1) * (grid + 1), np.int64)
    stride = grid + 1
    for (ix, iy), sgn in (((a[:, 0], a[:, 1]), 1), ((b[:, 0], a[:, 1]), -1),
                          ((a[:, 0], b[:, 1]), -1), ((b[:, 0], b[:, 1]), 1)):
        diff += np.bincount(ix * stride + iy, weights=sgn * weight,
                            minlength=len(diff)).astype(np.int64)
    return diff.reshape(stride, stride).cumsum(0).cumsum(1)[:grid, :grid]


def _clip_to_pyramid(tri: np.ndarray, axis: int, sign: float) -> tuple[np.ndarray, np.ndarray]:
    """The box (lo, hi) (n, 2) of the central projection of each triangle's part inside the
    cube face's pyramid (apex at the light, `sign` * x[axis] >= |x[b]|, |x[c]|): the triangles
    (n, 3, 3), relative to the light, clipped by the pyramid's four planes (Sutherland-Hodgman,
    vectorised); an empty part gives lo > hi."""
    b, c = [k for k in range(3) if k != axis]
    n = len(tri)
    poly = np.zeros((n, 7, 3))
    poly[:, :3] = tri
    count = np.full(n, 3)
    for other, s2 in ((b, 1.0), (b, -1.0), (c, 1.0), (c, -1.0)):
        def f(x):  # >= 0 inside: depth - s2 * x[other]
            return sign * x[..., axis] - s2 * x[..., other]
        out = np.zeros_like(poly)
        out_n = np.zeros(n, np.int64)
        rows = np.arange(n)
        for k in range(7):
            valid = k < count
            cur = poly[:, k]
            nxt = poly[rows, np.where(k + 1 < count, k + 1, 0)]
            fc, fn = f(cur), f(nxt)
            keep = valid & (fc >= 0)
            out[rows[keep], out_n[keep]] = cur[keep]
            out_n += keep
            cross = valid & ((fc >= 0) != (fn >= 0))
            t = np.where(cross, fc / np.where(cross, fc - fn, 1.0), 0.0)
            point = cur + t[:, None] * (nxt - cur)
            out[rows[cross], np.minimum(out_n[cross], 6)] = point[cross]
            out_n += cross
        poly, count = out, np.minimum(out_n, 7)
    depth = sign * poly[..., axis]
    valid = (np.arange(7)[None] < count[:, None]) & (depth > 0)
    safe = np.where(valid, depth, 1.0)
    uv = np.stack([poly[..., b] / safe, poly[..., c] / safe], axis=-1)
    lo = np.where(valid[..., None], uv, np.inf).min(axis=1)
    hi = np.where(valid[..., None], uv, -np.inf).max(axis=1)
    # the apex itself (depth 0) may be a vertex of the clipped part: its direction is any
    apex = ((np.arange(7)[None] < count[:, None]) & (depth <= 0)).any(axis=1)
    lo[apex], hi[apex] = -1.0, 1.0
    return np.clip(lo, -1.0, np.inf), np.clip(hi, -np.inf, 1.0)


def light_bound(corners: np.ndarray, object_of: np.ndarray, convex: np.ndarray,
                light4: np.ndarray, slack: float, grid: int = LIGHT_GRID) -> int:
    """An upper bound on the stencil count at any visible point for this light: the largest
    number of triangles that one ray leaving the light (or, for a directional light, one line
    along its direction) can cross, each closed convex object counted at most twice.

    The count at a point X is the number of triangles crossing the segment from X to the light
    (every triangle casts).  Directions from the light are binned on the six faces of a cube
    around it (central projection: a triangle with all corners in front of a face projects to
    the triangle of its projected corners, so its box of projected corners holds every
    direction that meets it; a triangle wholly behind the face's plane in none; one across that
    plane by the box of its part clipped to the face's pyramid).  A directional light's lines
    are binned on the plane perpendicular to it.  Each box grows by its triangle's `slack` (M,) (world units,
    `world_slack`) seen from the light, so that the rasterized volumes, a little off the exact
    ones, stay inside.  The bound is the largest cell's sum.

    corners : (M, 3, 3) float64;  object_of : (M,) int, each triangle's object;  convex :
    (n_objects,) bool, closed convex objects (`is_closed_convex`)."""
    faces = (_directional_faces(corners, light4, slack) if light4[3] == 0.0
             else _cube_faces(corners, light4, slack))
    bound = 0
    convex_of = convex[object_of]
    for lo, hi, meets in faces:
        bound = max(bound, _face_bound(lo, hi, meets, object_of, convex, convex_of, grid))
    return bound


def _directional_faces(corners: np.ndarray, light4: np.ndarray, slack) -> list[tuple]:
    """`light_bound`'s one face for a directional light: each triangle's box (lo, hi (M, 2),
    in [-1, 1] on the plane perpendicular to it, grown by its slack) and meets (M,) bool."""
    d = -np.asarray(light4[:3], np.float64)
    d = d / np.linalg.norm(d)
    e1 = np.cross(d, [1.0, 0.0, 0.0] if abs(d[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(d, e1)
    uv = np.stack([corners @ e1, corners @ e2], axis=-1)              # (M, 3, 2)
    lo, hi = uv.min(axis=1) - slack[:, None], uv.max(axis=1) + slack[:, None]
    centre = (lo.min(axis=0) + hi.max(axis=0)) / 2
    half = float((hi.max(axis=0) - lo.min(axis=0)).max()) / 2 * (1 + 1e-9) + 1e-30
    return [((lo - centre) / half, (hi - centre) / half, np.ones(len(lo), bool))]


def _cube_faces(corners: np.ndarray, light4: np.ndarray, slack) -> list[tuple]:
    """`light_bound`'s six cube faces around a point light: (lo, hi (M, 2), meets (M,) bool)
    per face, each triangle's box of directions grown by its slack seen from the light."""
    rel = corners - np.asarray(light4[:3], np.float64)                # (M, 3, 3)
    dist = np.linalg.norm(rel, axis=-1).min(axis=1)                   # nearest corner
    # the nearest point of a triangle may be nearer than its corners: its box's distance
    box_lo, box_hi = rel.min(axis=1), rel.max(axis=1)
    nearest = np.linalg.norm(np.maximum(np.maximum(box_lo, -box_hi), 0.0), axis=1)
    dist = np.minimum(dist, nearest)
    with np.errstate(divide="ignore"):
        margin = np.where(dist > 0, GNOMONIC_STRETCH * slack / dist, np.inf)
    faces = []
    for axis in range(3):
        b, c = [k for k in range(3) if k != axis]
        for sign in (1.0, -1.0):
            depth = sign * rel[..., axis]                             # (M, 3)
            front = (depth > 0).all(axis=1)
            safe = np.where(depth > 0, depth, 1.0)
            uv = np.stack([rel[..., b] / safe, rel[..., c] / safe], axis=-1)
            lo = np.where(front[:, None], uv.min(axis=1) - margin[:, None], -1.0)
            hi = np.where(front[:, None], uv.max(axis=1) + margin[:, None], 1.0)
            # a triangle across the face's plane: the box of its part in the pyramid
            across = ~front & ~(depth <= 0).all(axis=1)
            if across.any():
                c_lo, c_hi = _clip_to_pyramid(rel[across], axis, sign)
                lo[across] = c_lo - margin[across, None]
                hi[across] = c_hi + margin[across, None]
            # triangles whose box misses the face, or wholly behind its plane, meet no ray
            # through it
            behind = (depth <= 0).all(axis=1)
            meets = ~((lo > 1.0).any(axis=1) | (hi < -1.0).any(axis=1) | behind)
            lo, hi = np.nan_to_num(lo, neginf=-1.0), np.nan_to_num(hi, posinf=1.0)
            faces.append((lo, hi, meets))
    return faces


def _face_bound(lo, hi, meets, object_of, convex, convex_of, grid: int) -> int:
    """The largest cell's sum of one face's boxes (`light_bound`), each closed convex object
    counted at most twice."""
    # boxes that cover the whole face (triangles across its plane) add the same to every
    # cell; the grid spans the rest, zoomed to their extent
    whole = meets & (lo <= -1.0).all(axis=1) & (hi >= 1.0).all(axis=1)
    part = meets & ~whole
    base = int((whole & ~convex_of).sum()) + sum(
        min(int((whole & (object_of == o)).sum()), 2) for o in np.flatnonzero(convex))
    if not part.any():
        return base
    lo_p, hi_p = np.maximum(lo[part], -1.0), np.minimum(hi[part], 1.0)
    z_lo, z_hi = lo_p.min(axis=0), hi_p.max(axis=0)
    scale = np.maximum(z_hi - z_lo, 1e-300) / 2
    lo_z, hi_z = (lo_p - z_lo) / scale - 1.0, (hi_p - z_lo) / scale - 1.0
    obj = object_of[part]
    open_part = ~convex_of[part]
    cells = _binned_max(lo_z[open_part], hi_z[open_part], np.ones(int(open_part.sum())),
                        grid)
    for o in np.flatnonzero(convex):
        mine = obj == o
        if mine.any():
            cells = cells + np.minimum(
                _binned_max(lo_z[mine], hi_z[mine], np.ones(int(mine.sum())), grid), 2)
    # a convex object both whole-face and partial is capped twice: still at most 4 of its
    # crossings counted, a bound
    return base + int(cells.max())
