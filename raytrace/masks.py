"""Reference shadow masks, exactly as CONVENTIONS.md ("What lit means") defines them.

For light i and pixel p, lit[i, p] is True when geometry is visible at p's centre, its geometric
(face) normal flipped to face the camera points toward the light (n·l > 0), a spot light's cone
contains the point, and no geometry lies between the point and the light.  Everything is traced
on the scene's triangles (`Scene.triangles()`), the same ones the rasterizer draws: the exact
sphere is for images only.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from shadowvol.scene import DirectionalLight, PointLight, Scene, SpotLight

from .backends import PacketBackend, TriangleBackend, for_each_tile, make_backend
from .camera import RayGrid
from .switches import receiving, switched_backend
from .tolerances import (
    LIFT_HEIGHTS,
    OWN_HIT_RETRIES,
    frame_origin,
    light_margin,
    shadow_height,
    through_light,
)

# Rays per tile: big enough that a tile's fixed cost (numpy's per-call overhead, the kernels'
# set-up, the pool's hand-over: ~0.3 ms a tile) is small, small enough that two tiles in flight
# stay within a few tens of MiB (`raytrace.estimate`).  Swept at 7395f45 (load 0.0-0.4, medians
# of 7-11 interleaved rounds, 1280 x 720): 8k 86 ms, 16k 71, 32k 62-67, 64k 59-63, 96k 63,
# 128k 60 on the 100k scene, the same order on 1M and two bunnies; 64k against 32k: masks
# 0.94-0.97x, ground truth 0.90-0.96x (docs/speed.md).
MASK_TILE_RAYS = 1 << 16


class MaskTracer(NamedTuple):
    """A triangle backend holding all of a scene's triangles, with what the masks need per
    triangle: built once by `scene_backend`, reusable over many `shadow_masks` calls.

    tracer    : the backend (Embree or numpy), holding the triangles minus `origin`
    triangles : the per-triangle normals, planes and error weights (`_Triangles`), same frame
    origin    : (3,) float64, the frame's origin in world space (`tolerances.frame_origin`)
    """

    tracer: TriangleBackend
    triangles: "_Triangles"
    origin: np.ndarray


def scene_backend(scene: Scene, backend: str = "embree") -> MaskTracer:
    """The scene's triangles in a backend, ready for `shadow_masks` (build once, trace often),
    in the float32 frame of `tolerances.frame_origin` (the eye): float64 coordinates minus the
    origin, subtracted before anything is rounded.  Objects switched off (`cast_shadows`,
    `receive_shadows`) are traced as `raytrace.switches` says."""
    vertices, faces, _ = scene.triangles()
    origin = frame_origin(scene)
    tracer = switched_backend(scene, make_backend(backend, vertices - origin, faces), origin)
    return MaskTracer(tracer, _Triangles.of(tracer), origin)


class _Triangles(NamedTuple):
    """What the masks need per triangle, float64, in the backend's frame: normals_t (3, M)
    unit normals by winding, component-major (fast gathers); plane_d (M,) normal · corner;
    weight (M,) the `tolerances.error_weight` of its corners; fragile (M,) bool, a sliver
    (`tolerances.is_sliver`): its blocked shadow rays are checked by id."""

    normals_t: np.ndarray
    plane_d: np.ndarray
    weight: np.ndarray
    fragile: np.ndarray

    @classmethod
    def of(cls, tracer: TriangleBackend) -> "_Triangles":
        return cls(np.ascontiguousarray(tracer.normals.T), tracer.plane_d, tracer.weight,
                   tracer.fragile)


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot product of component-major vectors: (3, n) x (3, n) -> (n,)."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def shadow_masks(scene: Scene, backend: str | MaskTracer = "embree"
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The reference masks of `scene`.

    backend : "embree", "numpy", or a backend already built by `scene_backend(scene, ...)`
              (the benchmark reuses one; any other triangles would give wrong masks).
    Returns lit : (L, H, W) bool, lights in scene order, and coverage : (H, W) bool; row 0 at
    the top.

    Each pixel's visible triangle is found with the float32 pixel-centre ray (Embree); the hit
    point is then that triangle's plane cut by the exact float64 ray, and each light's shadow
    ray is the segment from it to the light, on that segment's own line, shortened only at its
    ends by float error bounds, the visible triangle excluded by id (see
    `raytrace.tolerances`).  Everything is traced in the frame of the backend's `origin`.

    Speed (this is the benchmark's hot path):
    * The image is cut into tiles of a few rows, which a thread pool with one thread per core
      traces start to finish: Embree and numpy's large operations release the GIL, so the
      arithmetic around the ray casts runs in parallel too, and a tile's arrays stay in cache.
    * Vectors are stored component-major, (3, n): numpy broadcasts a (3,) vector over (n, 3)
      rows ~10x slower than it runs along contiguous (n,) rows.
    """
    tracer, triangles, origin = (scene_backend(scene, backend) if isinstance(backend, str)
                                 else backend)
    H, W = scene.height, scene.width
    lit = np.zeros((len(scene.lights), H, W), bool)
    coverage = np.zeros((H, W), bool)
    rows_per_tile = max(1, MASK_TILE_RAYS // W)
    tiles = [slice(y, min(y + rows_per_tile, H)) for y in range(0, H, rows_per_tile)]
    camera = scene.camera.translated(-origin)
    grids = (RayGrid(camera, W, H, np.float32), RayGrid(camera, W, H, np.float64))
    reach = scene.extent  # a ray that starts farther than this from its point has left the scene
    lights = [_local_light(light, origin, triangles) for light in scene.lights]

    def trace_tile(rows: slice) -> None:
        lit[:, rows], coverage[rows] = _tile_masks(scene, tracer, triangles, grids, rows, reach,
                                                   lights)

    for_each_tile(trace_tile, tiles, tracer)
    return lit, coverage


class _LocalLight(NamedTuple):
    """A light in the backend's frame: the light itself, its position there ((3,) float64, or
    None for a directional light) and `tolerances.through_light`'s weight (0.0 if none)."""

    light: object
    position: np.ndarray | None
    through: float


def _local_light(light, origin: np.ndarray, triangles: "_Triangles") -> _LocalLight:
    if isinstance(light, DirectionalLight):
        return _LocalLight(light, None, 0.0)
    if not isinstance(light, (PointLight, SpotLight)):
        raise TypeError(f"not a light: {type(light).__name__}")
    position = light.position - origin
    try:   # in one pass where numba loads (the same number)
        from .maskkernels import through_light as one_pass
    except ImportError:
        return _LocalLight(light, position, through_light(
            triangles.normals_t.T, triangles.plane_d, triangles.weight, position))
    return _LocalLight(light, position, one_pass(triangles.normals_t, triangles.plane_d,
                                                 triangles.weight, position))


class _Hits(NamedTuple):
    """The primary hits of a tile (only the covered pixels), float64, vectors component-major,
    in the backend's frame.

    point : (3, h) float32, the hit point, computed in float64 on the plane of the hit
    triangle and rounded once (Embree takes float32 rays);  normal : (3, h) the triangle's unit
    normal by winding;  side : (h,) ±1, turns `normal` toward the camera;
    side_d : (h,) side · (normal · point);  height : (h,) the margin at the surface
    (`tolerances.shadow_height`);  tri : (h,) int64, the hit triangle (excluded by id);
    fragile : (h,) bool, it is a sliver (`_Triangles.fragile`);  depth : (h,) float64, the
    eye-space depth of p (p = eye + depth·v, v the pixel's direction of depth 1);
    point64 : (3, h) float64, p before rounding (where a grazing ray's lift is traced again).
    """

    point: np.ndarray
    normal: np.ndarray
    side: np.ndarray
    side_d: np.ndarray
    height: np.ndarray
    tri: np.ndarray
    fragile: np.ndarray
    depth: np.ndarray
    point64: np.ndarray


def _tile_masks(scene: Scene, tracer: TriangleBackend, triangles: _Triangles,
                grids: tuple[RayGrid, RayGrid], rows: slice, reach: float,
                lights: list[_LocalLight]) -> tuple[np.ndarray, np.ndarray]:
    """Masks of the image rows `rows`: lit (L, R, W) bool and coverage (R, W) bool."""
    shape = (rows.stop - rows.start, scene.width)
    covered, index, hit = _primary_hits(tracer, triangles, grids, rows,
                                        need_hits=bool(scene.lights))
    lit = np.zeros((len(scene.lights), covered.size), bool)
    if hit is not None:
        near = []
        for i, light in enumerate(lights):
            lit[i, index], pieces = _lit(tracer, light, hit, reach)
            near.append(pieces)
        # the near pieces of all the lights in one float64 query (its cost is mostly per call)
        rays = np.concatenate([p.rays for p in near])
        which = np.repeat(np.arange(len(near)), [len(p.rays) for p in near])
        pieces = _NearPieces(rays, np.concatenate([p.origin for p in near], axis=1),
                             np.concatenate([np.broadcast_to(p.direction, p.origin.shape)
                                             for p in near], axis=1),
                             np.concatenate([p.tmax for p in near]))
        blocked = _near_blocked(tracer, pieces, hit.tri[rays])
        lit[which[blocked], index[rays[blocked]]] = False
    return lit.reshape((-1,) + shape), covered.reshape(shape)


def _primary_hits(tracer: TriangleBackend, triangles: _Triangles,
                  grids: tuple[RayGrid, RayGrid], rows: slice, need_hits: bool = True
                  ) -> tuple[np.ndarray, np.ndarray, _Hits | None]:
    """The visible triangles of the image rows `rows`: covered (R*W,) bool, index (h,) int64
    (the covered pixels, row-major within the rows) and their `_Hits` (None when no pixel is
    covered or `need_hits` is False)."""
    if need_hits and isinstance(tracer, PacketBackend):
        return _packet_primary_hits(tracer, triangles, grids, rows)
    grid32, grid64 = grids
    view32 = grid32.directions(rows)
    tri = tracer.closest_triangle(grid32.origins(view32).T, view32.T, parallel=False)
    covered = tri >= 0
    index = np.flatnonzero(covered)
    if len(index) == 0 or not need_hits:
        return covered, index, None
    k = tri[index]
    # the exact (float64) pixel-centre directions of the covered pixels
    view = np.take(grid64.directions(rows), index, axis=1)
    normal = np.take(triangles.normals_t, k, axis=1)
    n_dot_v = _dot(normal, view)
    plane_d = np.take(triangles.plane_d, k)
    # The hit point: p = eye + s·v on the triangle's plane n·p = plane_d, so
    # s = (plane_d − n·eye) / (n·v), in float64 (the primary ray starts on the near plane, but
    # p does not depend on where along the ray it starts).
    eye = grid64.eye
    with np.errstate(divide="ignore", invalid="ignore"):  # a degenerate triangle has n = 0
        s = (plane_d - _dot(eye, normal)) / n_dot_v
    point64 = eye[:, None] + s * view
    point = point64.astype(np.float32)  # rounded once, for Embree
    side = np.where(n_dot_v > 0, -1.0, 1.0)
    # the bound of p's float error relative to planes through it (tolerances, item 3)
    height = shadow_height(np.take(triangles.weight, k) + _dot(np.abs(normal), np.abs(point64)))
    return covered, index, _Hits(point, normal, side, side * plane_d, height, k,
                                 np.take(triangles.fragile, k), s, point64)


def _packet_primary_hits(tracer: PacketBackend, triangles: _Triangles,
                         grids: tuple[RayGrid, RayGrid], rows: slice
                         ) -> tuple[np.ndarray, np.ndarray, _Hits | None]:
    """`_primary_hits` on Embree's packets, rays and hits made in numba
    (`raytrace.maskkernels.primary_hits`): the same arrays, bit for bit."""
    from . import maskkernels

    grid32, grid64 = grids
    intersect, _, scene, width = tracer.packets()
    tri, index, *fields = maskkernels.primary_hits(
        intersect, scene, width, maskkernels.BLOCK_ROWS, *rows.indices(grid32.height)[:2],
        grid32.row, grid32.col, grid32.eye, grid32.near, grid64.row, grid64.col, grid64.eye,
        triangles.normals_t, triangles.plane_d, triangles.weight, triangles.fragile)
    covered = tri >= 0
    return covered, index, (_Hits(*fields) if len(index) else None)


def _round_down32(x: np.ndarray) -> np.ndarray:
    """float64 (n,) -> the float32 values nearest below (or equal)."""
    y = x.astype(np.float32)
    return np.where(y > x, np.nextafter(y, np.float32(0)), y)


def _blocked(tracer: TriangleBackend, start: np.ndarray, direction: np.ndarray,
             tmax: np.ndarray | None, own: np.ndarray, fragile: np.ndarray) -> np.ndarray:
    """(n,) bool: is the shadow ray start + t·direction (0 < t < tmax) blocked by a triangle
    other than `own` (n,) int64, the triangle it leaves?  start (3, n) float32; direction
    (3, n) float32, or (3, 1) for all; tmax (n,) float32 or None (unbounded); fragile (n,)
    bool: `own` is a sliver, whose float32 arithmetic the height bound does not cover.

    One bounded occlusion query for all.  The rays it finds blocked that leave a sliver are
    cast again for their first hit, and where that is `own` (rounding: see
    `raytrace.tolerances`) cast on from that hit, at most OWN_HIT_RETRIES times, after which
    `own` is all they met: not blocked."""
    blocked = tracer.occluded(start.T, direction.T, tmax, parallel=False)
    todo = np.flatnonzero(blocked & fragile)
    if len(todo) and direction.shape[1] == 1:
        direction = np.broadcast_to(direction, start.shape)
    for _ in range(OWN_HIT_RETRIES):
        if len(todo) == 0:
            break
        o, d = start[:, todo], direction[:, todo]
        bound = None if tmax is None else tmax[todo]
        t, tri = tracer.first_hit(o.T, d.T, bound)
        blocked[todo] = tri >= 0
        again = tri == own[todo]
        todo, t = todo[again], t[again].astype(np.float32)
        start[:, todo] = o[:, again] + t * d[:, again]
        if tmax is not None:
            tmax[todo] = tmax[todo] - t
    blocked[todo] = False  # still only `own`: it cannot block its own segment
    return blocked


class _Segments(NamedTuple):
    """The shadow rays of a tile's hit points toward one light (see `_segments`).

    facing    : (h,) bool, n·l > 0 (and, for a spot light, inside the cone): lit unless blocked
    rays      : (r,) int64, the facing hits that need a shadow ray past the lift (the
                others are lit unless their `near` piece is blocked)
    start     : (3, r) float32;  direction : (3, r) float32, or (3, 1) for all
    tmax      : (r,) float32, or None (unbounded: a directional light)
    near      : `_NearPieces`, the pieces a long lift skips, traced again in float64
    """

    facing: np.ndarray
    rays: np.ndarray
    start: np.ndarray
    direction: np.ndarray
    tmax: np.ndarray | None
    near: "_NearPieces"


class _NearPieces(NamedTuple):
    """The start of the segments whose lift is longer than LIFT_HEIGHTS heights
    (`tolerances`, item 3b): rays (q,) int64, which hits; origin (3, q) float64, p itself;
    direction (3, q) float64, or (3, 1) for all; tmax (q,) float64, where the lifted start (or
    the segment's end, if nearer) is."""

    rays: np.ndarray
    origin: np.ndarray
    direction: np.ndarray
    tmax: np.ndarray

    def where(self, keep: np.ndarray) -> "_NearPieces":
        """The pieces where keep (q,) bool is True."""
        d = self.direction if self.direction.shape[1] == 1 else self.direction[:, keep]
        return _NearPieces(self.rays[keep], self.origin[:, keep], d, self.tmax[keep])


def _near_blocked(tracer: TriangleBackend, near: _NearPieces, own: np.ndarray) -> np.ndarray:
    """(q,) bool: is the piece of segment a lift skips blocked, in float64, by a triangle
    other than `own` (q,) int64 and those through p (`TriangleBackend.occluded_leaving`)?"""
    if len(near.rays) == 0:
        return np.zeros(0, bool)
    return tracer.occluded_leaving(near.origin.T, near.direction.T, near.tmax, own)


def _lit(tracer: TriangleBackend, local: _LocalLight, hit: _Hits, reach: float
         ) -> tuple[np.ndarray, "_NearPieces"]:
    """(h,) bool: which of the tile's hit points the light reaches: facing it, and their
    shadow ray (`_segments`) not blocked by a triangle other than their own (`_blocked`) --
    but for the near pieces a long lift skips (`_NearPieces`, those of the points lit so
    far), returned too: lit where `_near_blocked` finds them clear."""
    seg = receiving(tracer, local.light,
                    _segments(local, hit, reach, isinstance(tracer, PacketBackend)), hit)
    out = seg.facing.copy()
    out[seg.rays] = ~_blocked(tracer, seg.start, seg.direction, seg.tmax, hit.tri[seg.rays],
                              hit.fragile[seg.rays])
    return out, seg.near.where(out[seg.near.rays])  # those the rest of the segment left lit


def _segments(local: _LocalLight, hit: _Hits, reach: float, fused: bool = False
              ) -> _Segments:
    """The shadow rays of the tile's hit points toward one light.

    The shadow ray is the segment p -> light (p + t·l, 0 < t < 1, l = L − p) or the ray
    p + t·l (t > 0, l = −direction) on its own line; only its ends are cut: t > height/(n·l)
    at the surface (height `hit.height` above p's plane) and, for a point light,
    t < 1 − light_margin/|l|, and the hit triangle does not count (`_blocked`).  Where that
    lift is longer than LIFT_HEIGHTS heights, the piece it skips is `_Segments.near`.
    Origins and directions go to Embree as float32, component-major (embreex reads the
    transposed views without a copy).  fused: made in numba (`_fused_segments`), the same
    arrays."""
    if fused:
        return _fused_segments(local, hit, reach)
    if isinstance(local.light, DirectionalLight):
        return _directional_segments(local.light, hit, reach)
    return _point_segments(local, hit)


def _fused_segments(local: _LocalLight, hit: _Hits, reach: float) -> _Segments:
    """`_segments` made in numba, in one pass over the hits (`raytrace.maskkernels`)."""
    from . import maskkernels

    light = local.light
    if isinstance(light, DirectionalLight):
        toward = -light.direction
        facing, rays, start, k, tmax = maskkernels.directional_segments(
            toward, float(reach), hit.point, hit.normal, hit.side, hit.height)
        near = _NearPieces(k, hit.point64[:, k], toward[:, None], tmax)
        return _Segments(facing, rays, start, toward.astype(np.float32)[:, None], None, near)
    position = local.position
    spot = isinstance(light, SpotLight)
    axis = light.direction if spot else position
    cos_cutoff = np.float32(light.cos_cutoff if spot else 0.0)
    facing, rays, start, l, gap, k, tmax = maskkernels.point_segments(
        position, float(np.abs(position).max()), float(local.through), spot,
        np.asarray(axis, np.float64), cos_cutoff, hit.point, hit.normal, hit.side,
        hit.side_d, hit.height)
    origin = hit.point64[:, k]
    return _Segments(facing, rays, start, l, gap,
                     _NearPieces(k, origin, position[:, None] - origin, tmax))


def _long_lifts(rays: np.ndarray, near: np.ndarray, lift: np.ndarray, end, hit: _Hits,
                position: np.ndarray | None, toward: np.ndarray | None = None) -> _NearPieces:
    """The `_NearPieces` of the rays (r,) (hit indices) whose lift (r,) (world units) is
    longer than LIFT_HEIGHTS heights: from p to min(near, end) (in units of the direction,
    position − p toward a point light at position (3,), toward (3,) if position is None);
    the directions of these rays only are computed."""
    long = np.flatnonzero(lift > LIFT_HEIGHTS * hit.height[rays])
    tmax = np.minimum(near[long], end if np.ndim(end) == 0 else end[long])
    k = rays[long]
    origin = hit.point64[:, k]
    direction = toward[:, None] if position is None else position[:, None] - origin
    return _NearPieces(k, origin, direction, tmax)


def _directional_segments(light: DirectionalLight, hit: _Hits, reach: float) -> _Segments:
    """`_segments` toward a directional light: rays, unbounded, ending at the scene's reach."""
    f32 = np.float32
    toward = -light.direction
    n_dot_l = hit.side * _dot(toward, hit.normal)  # n facing the camera
    facing = n_dot_l > 0
    with np.errstate(divide="ignore"):
        near = hit.height / n_dot_l  # distance along the unit l
    cast = facing & (near < reach)  # a start beyond the scene's reach sees nothing
    toward32 = toward.astype(f32)
    start = hit.point.compress(cast, axis=1)
    start += near[cast].astype(f32) * toward32[:, None]
    c = np.flatnonzero(facing)
    near_c = near[c]
    pieces = _long_lifts(c, near_c, near_c, reach, hit, None, toward)
    # Unbounded: anything anywhere along the ray toward a directional light blocks it.
    return _Segments(facing, np.flatnonzero(cast), start, toward32[:, None], None, pieces)


def _point_segments(local: _LocalLight, hit: _Hits) -> _Segments:
    """`_segments` toward a point or spot light: segments, `light_margin` short of it."""
    f32 = np.float32
    light, position = local.light, local.position
    # n·(L − p) = n·L − n·p, and n·p = plane_d on the triangle's plane.
    n_dot_l = hit.side * _dot(position, hit.normal) - hit.side_d
    facing = n_dot_l > 0
    c = np.flatnonzero(facing)
    start = hit.point.compress(facing, axis=1)
    l = position.astype(f32)[:, None] - start
    length = np.sqrt(_dot(l, l))
    if isinstance(light, SpotLight):
        # Inside the cone: cos(angle between the spot's axis and the point) >= cos_cutoff.
        inside = -_dot(light.direction, l) >= light.cos_cutoff * length
        facing[c[~inside]] = False
        c, start, l, length = c[inside], start[:, inside], l[:, inside], length[inside]
    near = hit.height[c] / n_dot_l[c]                      # fractions of the segment
    length = length.astype(np.float64)
    end = 1.0 - light_margin(position, length, local.through) / length
    pieces = _long_lifts(c, near, near * length, end, hit, position)
    gap = end - near
    # Where the margins meet (gap <= 0: the light within `height` of the surface's plane)
    # nothing is strictly between the lift and the light's margin: only the near piece.
    cast = gap > 0
    if not cast.all():
        c, start, l, near, gap = c[cast], start[:, cast], l[:, cast], near[cast], gap[cast]
    start += near.astype(f32) * l
    gap = _round_down32(gap)  # Embree's tfar is float32: never let rounding lengthen the ray
    # Bounded: the rest of the segment, direction l not normalised, so it ends at tmax = gap.
    return _Segments(facing, c, start, l, gap, pieces)
