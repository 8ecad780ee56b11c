"""An area light as the exact visibility sees it (`raytrace.exact_soft`): its plane, its
outline in the plane's coordinates, its convex hull (the base of the pyramid from a point), its
area, and the grid its polygon booleans snap to.  A sphere light has none (SceneError).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from shadowvol.errors import require
from shadowvol.planes import default_plane_axes
from shadowvol.scene import AreaLight, SceneError

# GEOS's floating-point overlay is not robust where edges nearly coincide (two triangles that
# cover a light between them, their shared edge projected twice with roundings 1e-12 apart:
# their union came back as one of them).  Its snap-rounding overlay is: every polygon boolean
# here rounds its corners to a grid of this much of the light's extent (2^-44, ~6e-14: some
# 250 float64 spacings of a coordinate of the light's size, so the snapping is itself exact,
# and V moves by at most the rings' length times half of it over the area, ~1e-13).
OVERLAY_GRID = 2.0 ** -44


class FramedLight(NamedTuple):
    """An area light in the frame: centre (3,), unit emitting normal (3,), axes (2, 3) (u, v),
    hull (k, 2) its convex outline, counter-clockwise (the pyramid's base), outline (m, 2)
    its own (None: the hull), radius (a disk, else None), area; grid: the snap-rounding grid
    of its polygon booleans (OVERLAY_GRID of its size, a power of two)."""

    center: np.ndarray
    normal: np.ndarray
    axes: np.ndarray
    hull: np.ndarray
    outline: np.ndarray | None
    radius: float | None
    area: float
    grid: float


def frame_light(light: AreaLight, origin: np.ndarray, key: str) -> FramedLight:
    """`light` in the frame of `origin` (its centre less the origin); SceneError naming `key`
    for a sphere light."""
    if light.shape == "sphere":
        raise SceneError(f"{key}.type", "a sphere light has no exact visibility (the part of "
                                        "a sphere's surface seen past occluders is bounded by "
                                        "small-circle arcs; not computed); use rect, disk or "
                                        "polygon, or the sampled lit_count")
    center = light.center - origin
    # a writable copy, as every other array here (and the tests' lights) is: numba compiles a
    # kernel once per array type, and a read-only array is another type
    normal = np.array(light.normal)
    u, v = default_plane_axes(normal)
    axes = np.stack([u, v])
    if light.shape == "rect":
        w, h = light.size / 2
        hull = np.array([[-w, -h], [w, -h], [w, h], [-w, h]])
        return FramedLight(center, normal, axes, hull, None, None,
                           float(light.size.prod()), _grid(hull))
    if light.shape == "disk":
        r = light.radius
        hull = np.array([[-r, -r], [r, -r], [r, r], [-r, r]])
        return FramedLight(center, normal, axes, hull, None, r, float(np.pi * r * r),
                           _grid(hull))
    shapely = shapely_module()
    outline = (light.vertices - light.center) @ axes.T
    ring = shapely.Polygon(outline)
    hull = np.array(ring.convex_hull.exterior.coords)[:-1]
    if shapely.is_ccw(shapely.LinearRing(hull)) is False:
        hull = hull[::-1]
    return FramedLight(center, normal, axes, hull, outline, None, float(ring.area),
                       _grid(hull))


def _grid(hull: np.ndarray) -> float:
    """The power of two OVERLAY_GRID of the light's extent (hull (k, 2))."""
    return 2.0 ** (math.ceil(math.log2(np.abs(hull).max())) + math.log2(OVERLAY_GRID))


def shapely_module():
    return require("shapely", "exact visibility (visibility_exact, irradiance_exact)",
                   extra="exact")
