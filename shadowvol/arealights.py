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
