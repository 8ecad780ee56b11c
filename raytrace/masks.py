"""Reference shadow masks, exactly as CONVENTIONS.md ("What lit means") defines them.

For light i and pixel p, lit[i, p] is True when geometry is visible at p's centre, its geometric
(face) normal flipped to face the camera points toward the light (n·l > 0), a spot light's cone
contains the point, and no geometry lies between the point and the light.  Everything is traced
on the scene's triangles (`Scene.triangles()`), the same ones the rasterizer draws: the exact
sphere is for images only.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from typing import NamedTuple

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
    # and the ray–plane formula n·p = plane_d gives  s = (plane_d − n·eye) / (n·v).  Only the
    # distance s is computed here; each light builds the points it needs (n·l > 0) from it.
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(covered, (plane_d - grid.eye @ normal) / n_dot_v, f32(0))
    hit = _Hits(grid.eye, view, s, normal, side * offset, plane_d * side, covered)
    for i, light in enumerate(scene.lights):
        lit[i] = _lit(tracer, light, hit).reshape(shape)
    return lit, covered.reshape(shape)


class _Hits(NamedTuple):
    """The primary hits of a tile, all float32, vectors component-major.

    eye : (3,);  view : (3, n) ray directions;  s : (n,) the hit point is eye + s·view;
    normal : (3, n) unit face normals by winding;  step : (n,) the surface offset times ±1, the
    sign that turns `normal` toward the camera, so a shadow ray starts at p + step·normal;
    side_d : (n,) (±1)·(normal·p);  covered : (n,) bool, where there is a surface at all.
    """

    eye: np.ndarray
    view: np.ndarray
    s: np.ndarray
    normal: np.ndarray
    step: np.ndarray
    side_d: np.ndarray
    covered: np.ndarray

    def shadow_starts(self, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Hit points (3, k) of the rays `c` (k,) int, and where their shadow rays start."""
        p = self.eye[:, None] + self.s[c] * np.take(self.view, c, axis=1)
        return p, p + self.step[c] * np.take(self.normal, c, axis=1)


def _lit(tracer: TriangleBackend, light, hit: _Hits) -> np.ndarray:
    """(n,) bool: which of the tile's n hit points the light reaches."""
    sign = np.sign(hit.step)
    if isinstance(light, DirectionalLight):
        toward = (-light.direction).astype(np.float32)
        # n·l > 0, with n facing the camera.
        candidate = hit.covered & (sign * (toward @ hit.normal) > 0)
        c = np.flatnonzero(candidate)
        _, start = hit.shadow_starts(c)
        # Unbounded: anything anywhere along the ray toward a directional light blocks it.
        candidate[c] = ~tracer.occluded(start.T, toward[None], None, parallel=False)
        return candidate
    if not isinstance(light, (PointLight, SpotLight)):
        raise TypeError(f"not a light: {type(light).__name__}")
    position = light.position.astype(np.float32)
    # n·(L − p) = n·L − n·p, and n·p = plane_d on the triangle's plane.
    candidate = hit.covered & (sign * (position @ hit.normal) - hit.side_d > 0)
    c = np.flatnonzero(candidate)
    p, start = hit.shadow_starts(c)
    if isinstance(light, SpotLight):
        # Inside the cone: cos(angle between the spot's axis and the point) >= cos_cutoff.
        from_light = p - position[:, None]
        inside = light.direction.astype(np.float32) @ from_light >= \
            np.float32(light.cos_cutoff) * np.sqrt((from_light * from_light).sum(axis=0))
        candidate[c[~inside]] = False
        c, start = c[inside], start[:, inside]
    # Bounded: the segment from the start to the light, direction not normalised, so tmax = 1.
    candidate[c] = ~tracer.occluded(start.T, (position[:, None] - start).T, 1.0, parallel=False)
    return candidate
