"""Sample points of area lights: the unit-square patterns and their maps onto the shapes.

Pure numpy, no scene types (the scene model, `shadowvol.lights.AreaLight`, calls these once when
it is built).  Every map below is area-preserving, so a stratified pattern stays stratified:
each cell of the unit square becomes a piece of the light of equal area.

* `stratified`: an nu x nv grid of cells (`grid_shape`), one point per cell, jittered inside it
  with `numpy.random.default_rng(seed)`; cells in row-major order (u fastest).
* `halton`: points 1..N of the Halton sequence in bases 2 and 3 (point 0 is the corner (0, 0));
  a seed other than 0 shifts every point by one random offset modulo 1 (Cranley-Patterson
  rotation), seed 0 leaves the sequence as it is.
"""

from __future__ import annotations

import math

import numpy as np

PATTERNS = ("stratified", "halton")


def grid_shape(n: int) -> tuple[int, int]:
    """(nu, nv) with nu * nv == n, as square as n allows (nv the largest divisor <= sqrt n,
    nu >= nv); a prime n gives an n x 1 strip."""
    nv = max(d for d in range(1, math.isqrt(n) + 1) if n % d == 0)
    return n // nv, nv


def unit_square(n: int, pattern: str, seed: int, grid: tuple[int, int] | None = None
                ) -> np.ndarray:
    """(n, 2) float64 points in [0, 1)^2.  `grid` (nu, nv) overrides `grid_shape(n)` for the
    stratified pattern (nu * nv must be n)."""
    rng = np.random.default_rng(seed)
    if pattern == "stratified":
        nu, nv = grid_shape(n) if grid is None else grid
        j, i = np.divmod(np.arange(n), nu)  # i along u (fastest), j along v
        jitter = rng.random((n, 2))
        return np.stack([(i + jitter[:, 0]) / nu, (j + jitter[:, 1]) / nv], axis=1)
    if pattern == "halton":
        index = np.arange(1, n + 1)
        points = np.stack([_radical_inverse(index, 2), _radical_inverse(index, 3)], axis=1)
        if seed:
            points = (points + rng.random(2)) % 1.0
        return points
    raise ValueError(f"unknown pattern {pattern!r} (one of: {', '.join(PATTERNS)})")


def _radical_inverse(index: np.ndarray, base: int) -> np.ndarray:
    """(n,) float64: the digits of `index` (n,) int in `base` mirrored about the point."""
    out = np.zeros(len(index))
    scale = 1.0 / base
    rest = index.copy()
    while rest.any():
        rest, digit = np.divmod(rest, base)
        out += digit * scale
        scale /= base
    return out


def rect_points(uv: np.ndarray, center: np.ndarray, u: np.ndarray, v: np.ndarray,
                size: np.ndarray) -> np.ndarray:
    """(n, 3): uv (n, 2) in [0, 1)^2 on the rectangle centre ± size/2 along unit axes u, v."""
    return center + ((uv[:, :1] - 0.5) * size[0]) * u + ((uv[:, 1:] - 0.5) * size[1]) * v


def disk_points(uv: np.ndarray, center: np.ndarray, u: np.ndarray, v: np.ndarray,
                radius: float) -> np.ndarray:
    """(n, 3): uv (n, 2) on the disk of `radius` spanned by unit axes u, v, by Shirley and
    Chiu's concentric map (area-preserving, and it keeps neighbouring cells neighbours)."""
    a, b = 2.0 * uv[:, 0] - 1.0, 2.0 * uv[:, 1] - 1.0
    first = np.abs(a) > np.abs(b)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(first, a, b)
        phi = np.where(first, (math.pi / 4) * (b / a), math.pi / 2 - (math.pi / 4) * (a / b))
    phi = np.where((a == 0) & (b == 0), 0.0, phi)
    x, y = radius * r * np.cos(phi), radius * r * np.sin(phi)
    return center + x[:, None] * u + y[:, None] * v


def sphere_points(uv: np.ndarray, center: np.ndarray, radius: float) -> np.ndarray:
    """(n, 3): uv (n, 2) on the sphere's surface, area-preserving (Archimedes: height
    1 - 2u along world y, azimuth 2 pi v)."""
    y = 1.0 - 2.0 * uv[:, 0]
    ring = np.sqrt(np.maximum(0.0, 1.0 - y * y))
    phi = 2.0 * math.pi * uv[:, 1]
    return center + radius * np.stack([ring * np.cos(phi), y, ring * np.sin(phi)], axis=1)


def polygon_frame(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """A plane polygon's unit normal by Newell's method (its vertices (m, 3) run
    counter-clockwise seen from the side it points to), its area centroid (3,) and area."""
    local = vertices - vertices[0]  # far from the origin the cross products of the corners
    nxt = np.roll(local, -1, axis=0)  # themselves would lose the normal to rounding
    newell = 0.5 * np.cross(local, nxt).sum(axis=0)
    area = float(np.linalg.norm(newell))
    normal = newell / area if area > 0 else newell
    fan = np.cross(vertices[1:-1] - vertices[0], vertices[2:] - vertices[0]) @ normal / 2
    centroids = (vertices[0] + vertices[1:-1] + vertices[2:]) / 3
    if area == 0 or fan.sum() == 0:  # no area (the caller refuses it): the corners' mean
        return normal, vertices.mean(axis=0), area
    return normal, (fan[:, None] * centroids).sum(axis=0) / fan.sum(), area


def triangulate(points: np.ndarray) -> np.ndarray:
    """(m - 2, 3) int64: the triangles of the simple polygon `points` (m, 2), counter-clockwise,
    by ear clipping (O(m^3), lights have few vertices): a corner is cut off when it turns left
    and no other vertex lies in its triangle."""
    left = list(range(len(points)))
    out = []
    while len(left) > 3:
        for k in range(len(left)):
            a, b, c = left[k - 1], left[k], left[(k + 1) % len(left)]
            if _cross2(points[a], points[b], points[c]) <= 0:
                continue
            others = [i for i in left if i not in (a, b, c)]
            if not any(_inside(points[i], points[a], points[b], points[c]) for i in others):
                out.append((a, b, c))
                del left[k]
                break
        else:  # rounding left no ear: the rest is (nearly) a line of zero area
            break
    out.append(tuple(left[:3]))
    return np.array(out, np.int64)


def _cross2(a, b, c) -> float:
    return float((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))


def _inside(q, a, b, c) -> bool:
    return _cross2(a, b, q) >= 0 and _cross2(b, c, q) >= 0 and _cross2(c, a, q) >= 0


def polygon_points(uv: np.ndarray, corners: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(n, 3): uv (n, 2) in [0, 1)^2 on the polygon made of `triangles` (t, 3) of `corners`
    (m, 3), area-preserving: u picks a triangle by its share of the area (and is stretched
    back to [0, 1) inside it), then (u, v) -> the triangle by the square-root map."""
    a, b, c = (corners[triangles[:, k]] for k in range(3))
    areas = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    edges = np.concatenate([[0.0], np.cumsum(areas) / areas.sum()])
    k = np.clip(np.searchsorted(edges, uv[:, 0], side="right") - 1, 0, len(areas) - 1)
    s = np.clip((uv[:, 0] - edges[k]) / (edges[k + 1] - edges[k]), 0.0, 1.0)
    root = np.sqrt(s)[:, None]
    t = uv[:, 1:]
    return (1 - root) * a[k] + root * (1 - t) * b[k] + root * t * c[k]
