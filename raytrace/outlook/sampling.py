"""The sample patterns of distributed ray tracing (Cook, Porter, Carpenter 1984), seeded.

Every dimension of a pixel's N samples (the position in the pixel, the point on the lens, the
glossy reflection of each generation) is stratified on its own, and the strata of different
dimensions are paired by an independent random permutation per pixel: sample k's lens stratum
says nothing about its pixel stratum (Cook's "the samples must not be correlated").

The layout of N strata in the unit square: a sqrt(N) x sqrt(N) grid when N is a perfect
square, else N-rooks (Shirley 1991): N columns and N rows, sample k in column k and row π(k),
so each axis alone is stratified into N.  One pixel sample (N = 1) is the centre (0.5, 0.5),
not jittered: `--spp 1` is the image of the pixel centres.
"""

from __future__ import annotations

import math

import numpy as np

FILTERS = ("box", "tent")


def stratified(rng: np.random.Generator, pixels: int, spp: int,
               centre: bool = False) -> np.ndarray:
    """(pixels, spp, 2) float64 in [0, 1)²: each pixel's spp jittered samples, one per
    stratum of the layout above, in an order drawn at random per pixel.  One sample is
    (0.5, 0.5) if `centre` (the pixel position), else uniform (a lens or glossy sample)."""
    if spp == 1 and centre:
        return np.full((pixels, 1, 2), 0.5)
    m = math.isqrt(spp)
    if m * m == spp:
        k = np.arange(spp)
        cell = np.stack([k % m, k // m], axis=-1).astype(np.float64)
        u = (cell[None] + rng.random((pixels, spp, 2))) / m
    else:  # N-rooks: column k, row π(k)
        rows = _permutations(rng, pixels, spp)
        cell = np.stack([np.broadcast_to(np.arange(spp), (pixels, spp)), rows], axis=-1)
        u = (cell + rng.random((pixels, spp, 2))) / spp
    return u[np.arange(pixels)[:, None], _permutations(rng, pixels, spp)]  # a fresh pairing


def _permutations(rng: np.random.Generator, pixels: int, spp: int) -> np.ndarray:
    """(pixels, spp) int: a random permutation of 0 .. spp - 1 per pixel."""
    return rng.permuted(np.broadcast_to(np.arange(spp), (pixels, spp)), axis=1)


def pixel_offsets(u: np.ndarray, pixel_filter: str) -> np.ndarray:
    """Sample positions in pixel units relative to the pixel's corner, (…, 2), from stratified
    u (…, 2) in [0, 1)².  `box`: u itself (the pixel's square).  `tent`: u warped through
    the tent's inverse CDF to the triangle filter of radius 1 pixel about the centre, so the
    plain mean of the samples is the tent-filtered pixel (importance sampling, no weights).
    Either way u = 0.5 is the centre."""
    if pixel_filter == "box":
        return u
    if pixel_filter != "tent":
        raise ValueError(f"filter must be one of {', '.join(FILTERS)}, got {pixel_filter!r}")
    a = 2.0 * u
    return 0.5 + np.where(a < 1.0, np.sqrt(a) - 1.0, 1.0 - np.sqrt(np.maximum(2.0 - a, 0.0)))


def concentric_disk(u: np.ndarray) -> np.ndarray:
    """Shirley and Chiu's map of the unit square (…, 2) onto the unit disk (…, 2): keeps the
    strata (and u = 0.5 at the centre), unlike r = sqrt(u₁)."""
    a = 2.0 * u - 1.0
    x, y = a[..., 0], a[..., 1]
    wide = np.abs(x) > np.abs(y)
    safe = np.where(wide, x, y)
    safe = np.where(safe == 0.0, 1.0, safe)
    r = np.where(wide, x, y)
    theta = np.where(wide, (np.pi / 4) * (y / safe), np.pi / 2 - (np.pi / 4) * (x / safe))
    return np.stack([r * np.cos(theta), r * np.sin(theta)], axis=-1)


def phong_exponent(roughness: np.ndarray) -> np.ndarray:
    """The Phong lobe exponent of a roughness in (0, 1]: 2 / r² − 2 (Walter et al.'s match to
    a Beckmann slope r), so r = 1 is the uniform hemisphere and r → 0 the mirror."""
    return 2.0 / np.square(roughness) - 2.0


def glossy(mirror: np.ndarray, normal: np.ndarray, roughness: np.ndarray,
           u: np.ndarray) -> np.ndarray:
    """Glossy reflection directions (k, 3), unit: the Phong lobe cos^e about the unit mirror
    directions (k, 3), e = `phong_exponent(roughness)` (k,) in (0, 1], sampled from u (k, 2) in
    [0, 1)².  A direction below the surface (unit normals (k, 3) on the ray's side) is folded
    back above it, so every ray leaves on the side it came from and the lobe's weight is 1."""
    cos_t = u[:, 0] ** (1.0 / (phong_exponent(roughness) + 1.0))
    sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
    phi = 2.0 * np.pi * u[:, 1]
    helper = np.where(np.abs(mirror[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t1 = np.cross(helper, mirror)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(mirror, t1)
    d = (cos_t[:, None] * mirror + (sin_t * np.cos(phi))[:, None] * t1
         + (sin_t * np.sin(phi))[:, None] * t2)
    below = np.einsum("ij,ij->i", d, normal)
    d = d - 2.0 * np.minimum(below, 0.0)[:, None] * normal
    return d / np.linalg.norm(d, axis=1, keepdims=True)
