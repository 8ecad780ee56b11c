"""Reference shadow masks, exactly as CONVENTIONS.md ("What lit means") defines them.

For light i and pixel p, lit[i, p] is True when geometry is visible at p's centre, its geometric
(face) normal flipped to face the camera points toward the light (n·l > 0), a spot light's cone
contains the point, and no geometry lies between the point and the light.  Everything is traced
on the scene's triangles (`Scene.triangles()`), the same ones the rasterizer draws: the exact
sphere is for images only.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np

from shadowvol.scene import DirectionalLight, PointLight, Scene, SpotLight

from .backends import TriangleBackend, make_backend
from .camera import RayGrid
from .tolerances import surface_offset

# Rays per tile: big enough that numpy's per-call overhead is small, small enough that a
# tile's arrays stay in cache and come from the allocator's free list, not fresh pages.
MASK_TILE_RAYS = 1 << 15


def scene_backend(scene: Scene, backend: str = "embree") -> TriangleBackend:
    """A triangle backend holding all of the scene's triangles (for `shadow_masks`)."""
    vertices, faces, _ = scene.triangles()
    return make_backend(backend, vertices, faces)


def shadow_masks(scene: Scene, backend: str | TriangleBackend = "embree"
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The reference masks of `scene`.

    backend : "embree", "numpy", or a backend already built by `scene_backend(scene, ...)`
              (the benchmark reuses one; any other triangles would give wrong masks).
    Returns lit : (L, H, W) bool, lights in scene order, and coverage : (H, W) bool; row 0 at
    the top.

    Speed (this is the benchmark's hot path):
    * The image is cut into tiles of a few rows, which a thread pool with one thread per core
      traces start to finish: Embree and numpy's large operations release the GIL, so the
      arithmetic around the ray casts runs in parallel too, and a tile's arrays stay in cache.
    * Vectors are stored component-major, (3, n): numpy broadcasts a (3,) vector over (n, 3)
      rows ~10x slower than it runs along contiguous (n,) rows.  Embree reads the transposed
      views as they are (strided), without a copy.
    * The arithmetic is float32: Embree traces in float32 anyway, and so does the rasterizer
      these masks are compared with.  A hit point is accurate to ~1e-7 of the scene's length
      scale, three orders of magnitude inside the surface offset.
    """
    tracer = scene_backend(scene, backend) if isinstance(backend, str) else backend
    H, W = scene.height, scene.width
    lit = np.zeros((len(scene.lights), H, W), bool)
    coverage = np.zeros((H, W), bool)
    rows_per_tile = max(1, MASK_TILE_RAYS // W)
    tiles = [slice(y, min(y + rows_per_tile, H)) for y in range(0, H, rows_per_tile)]
    threads = min(getattr(tracer, "threads", 1), len(tiles))
    grid = RayGrid(scene.camera, W, H, np.float32)
    offset = np.float32(surface_offset(scene))

    def trace_tile(rows: slice) -> None:
        lit[:, rows], coverage[rows] = _tile_masks(scene, tracer, grid, rows, offset)

    if threads == 1:
        for rows in tiles:
            trace_tile(rows)
    else:
        with ThreadPoolExecutor(threads) as pool:
            list(pool.map(trace_tile, tiles))  # list(): re-raises a tile's exception here
    return lit, coverage


def _tile_masks(scene: Scene, tracer: TriangleBackend, grid: RayGrid, rows: slice,
                offset: np.float32) -> tuple[np.ndarray, np.ndarray]:
    """Masks of the image rows `rows`: lit (L, R, W) bool and coverage (R, W) bool.
    All vectors (3, n) float32; see `shadow_masks`."""
    shape = (rows.stop - rows.start, scene.width)
    f32 = np.float32
    view = grid.directions(rows)
    tri = tracer.closest_triangle(grid.origins(view).T, view.T, parallel=False)
    covered = tri >= 0
    lit = np.zeros((len(scene.lights),) + shape, bool)
    if not covered.any() or not scene.lights:
        return lit, covered.reshape(shape)
    # Gather for every ray (a miss, tri = -1, reads the last triangle; `covered` masks it out
    # below): cheaper than compressing to the hits first.
    normal = np.take(tracer.normals_t32, tri, axis=1)  # by winding; `side` faces the camera
    plane_d = np.take(tracer.plane_d32, tri)
    n_dot_v = (normal * view).sum(axis=0)
    side = np.where(n_dot_v > 0, f32(-1), f32(1))
    # The hit point.  Every primary ray is o = eye + near·v, so p = eye + s·v with s = near + t,
    # and the ray–plane formula n·p = plane_d gives  s = (plane_d − n·eye) / (n·v).
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(covered, (plane_d - grid.eye @ normal) / n_dot_v, f32(0))
    point = grid.eye[:, None] + s * view
    for i, light in enumerate(scene.lights):
        lit[i] = _lit(tracer, light, point, normal, side * offset, plane_d * side,
                      covered).reshape(shape)
    return lit, covered.reshape(shape)


def _lit(tracer: TriangleBackend, light, point, normal, step, side_d, covered) -> np.ndarray:
    """(n,) bool: which of n surface points the light reaches.

    point : (3, n) float32;  normal : (3, n) unit face normals by winding;  step : (n,) the
    surface offset times ±1, the sign that turns `normal` toward the camera, so a shadow ray
    starts at point + step·normal;  side_d : (n,) (±1)·(normal·point);  covered : (n,) bool,
    where there is a surface at all.
    """
    sign = np.sign(step)
    if isinstance(light, DirectionalLight):
        toward = (-light.direction).astype(np.float32)
        candidate = covered & (sign * (toward @ normal) > 0)  # n·l > 0, n facing the camera
        c = np.flatnonzero(candidate)
        start = np.take(point, c, axis=1) + step[c] * np.take(normal, c, axis=1)
        # Unbounded: anything anywhere along the ray toward a directional light blocks it.
        candidate[c] = ~tracer.occluded(start.T, toward[None], None, parallel=False)
        return candidate
    if not isinstance(light, (PointLight, SpotLight)):
        raise TypeError(f"not a light: {type(light).__name__}")
    position = light.position.astype(np.float32)
    # n·(L − p) = n·L − n·p, and n·p = plane_d on the triangle's plane.
    candidate = covered & (sign * (position @ normal) - side_d > 0)
    c = np.flatnonzero(candidate)
    p = np.take(point, c, axis=1)
    if isinstance(light, SpotLight):
        # Inside the cone: cos(angle between the spot's axis and the point) >= cos_cutoff.
        from_light = p - position[:, None]
        inside = light.direction.astype(np.float32) @ from_light >= \
            np.float32(light.cos_cutoff) * np.sqrt((from_light * from_light).sum(axis=0))
        candidate[c[~inside]] = False
        c, p = c[inside], p[:, inside]
    start = p + step[c] * np.take(normal, c, axis=1)
    # Bounded: the segment from the start to the light, direction not normalised, so tmax = 1.
    candidate[c] = ~tracer.occluded(start.T, (position[:, None] - start).T, 1.0, parallel=False)
    return candidate
