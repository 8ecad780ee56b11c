"""Where radiosity's form-factor rays go: stratified points of the unit square, mapped onto the
cosine-weighted hemisphere by Shirley and Chiu's concentric disk (Malley's method), with a
share of them sent into a window of the square around the emitters.

Why the window: a patch sees the small Cornell light in about 1 % of its hemisphere, so plain
cosine rays find it a few dozen times each and the walls' direct light came out noisy
(±1-2 % per wall at 4096 rays).  The square is split into the window R1 (measure w1 of the
cosine measure, the map being area-preserving) and the rest R2 (w2 = 1 - w1); k1 rays are
stratified over R1 and k - k1 over R2, and a ray counts w1 / k1 or w2 / (k - k1).  That is
stratified sampling with unequal allocation: unbiased for any window, and a patch's weights sum
to exactly w1 + w2 = 1, so every ray still lands on exactly one patch and a closed box's rows
sum to one (the furnace stays exactly uniform).  The window only decides the variance: it is
the bounding box, in the square, of the emitters' corners seen from the patch's corners and
centre (corners behind the patch's plane taken on the disk's rim, where the emitter's edges
cross the horizon), padded by `WINDOW_PAD` (the images of its edges bulge); patches whose
window would be most of the square, or that see no emitter corner, get none.
"""

from __future__ import annotations

import numpy as np

from .brdf import frame

EMITTER_SHARE = 0.25  # the fraction of a patch's rays sent into its emitter window
WINDOW_PAD = 0.25  # the window's padding on each side, as a fraction of its size ...
WINDOW_MARGIN = 0.02  # ... plus this much of the square
WINDOW_MAX = 0.5  # a window larger than this share of the square is not worth it
HORIZON_COS = 1e-3  # an emitter corner this close to the patch's plane counts as on the rim
MIN_SPLIT_RAYS = 8  # fewer rays a patch than this: no window


def stratified(rng: np.random.Generator, m: int, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Two (m, k) float64 arrays: for each of m patches, k points of the unit square, one in
    each cell of a g x (k // g) grid (g = floor(sqrt k)), the k - g (k // g) left over uniform,
    in random order.  Each point is uniform on its own (estimates stay unbiased); together
    they cover the square evenly."""
    g = max(1, int(np.sqrt(k)))
    h = k // g
    cell = np.arange(g * h)
    a = np.concatenate([(cell // h + rng.random((m, g * h))) / g, rng.random((m, k - g * h))],
                       axis=1)
    b = np.concatenate([(cell % h + rng.random((m, g * h))) / h, rng.random((m, k - g * h))],
                       axis=1)
    order = rng.permuted(np.broadcast_to(np.arange(k), (m, k)), axis=1)
    return np.take_along_axis(a, order, axis=1), np.take_along_axis(b, order, axis=1)


def concentric_disk(u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Shirley and Chiu's map of the unit square onto the unit disk, area-preserving and
    continuous both ways: radius, azimuth, same shapes as u, v."""
    a, b = 2.0 * u - 1.0, 2.0 * v - 1.0
    first = np.abs(a) > np.abs(b)
    radius = np.where(first, a, b)
    safe = np.where(radius == 0.0, 1.0, radius)
    phi = np.where(first, np.pi / 4 * b / safe, np.pi / 2 - np.pi / 4 * a / safe)
    return np.abs(radius), np.where(radius < 0.0, phi + np.pi, phi)


def square_of_disk(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The inverse of `concentric_disk`: points (x, y) of the unit disk -> (u, v)."""
    r = np.hypot(x, y)
    ph = np.mod(np.arctan2(y, x) + np.pi / 4, 2 * np.pi) - np.pi / 4  # [-pi/4, 7pi/4)
    sector = np.floor((ph + np.pi / 4) / (np.pi / 2)).astype(int).clip(0, 3)
    s = 4.0 / np.pi
    a = np.choose(sector, [r, r * (np.pi / 2 - ph) * s, -r, -r * (3 * np.pi / 2 - ph) * s])
    b = np.choose(sector, [r * ph * s, r, -r * (ph - np.pi) * s, -r])
    return (a + 1.0) / 2.0, (b + 1.0) / 2.0


def emitter_windows(corners: np.ndarray, normals: np.ndarray, emitters: np.ndarray,
                    own: np.ndarray) -> np.ndarray:
    """(m, 4) windows (u0, u1, v0, v1) of the square for patches with corners (m, 3, 3) and
    outward normals (m, 3), around emitter corners (e, 3); rows of `own` (m,) bool (the
    emitters' own patches) and patches that get no window are all zero."""
    m = len(corners)
    window = np.zeros((m, 4))
    if m == 0 or len(emitters) == 0:
        return window
    t, b = frame(normals)
    origins = np.concatenate([corners, corners.mean(axis=1, keepdims=True)], axis=1)  # (m,4,3)
    w = emitters[None, None] - origins[:, :, None]  # (m, 4, e, 3)
    w /= np.maximum(np.linalg.norm(w, axis=3, keepdims=True), 1e-300)  # 0: no window
    z = np.einsum("mose,me->mos", w, normals)
    x, y = np.einsum("mose,me->mos", w, t), np.einsum("mose,me->mos", w, b)
    below = z <= HORIZON_COS  # seen across the horizon: its image goes to the disk's rim
    rim = np.maximum(np.hypot(x, y), 1e-300)
    u, v = square_of_disk(np.where(below, x / rim, x), np.where(below, y / rim, y))
    u, v = u.reshape(m, -1), v.reshape(m, -1)
    lo_u, hi_u, lo_v, hi_v = u.min(axis=1), u.max(axis=1), v.min(axis=1), v.max(axis=1)
    pad_u = WINDOW_PAD * (hi_u - lo_u) + WINDOW_MARGIN
    pad_v = WINDOW_PAD * (hi_v - lo_v) + WINDOW_MARGIN
    window = np.stack([np.maximum(lo_u - pad_u, 0.0), np.minimum(hi_u + pad_u, 1.0),
                       np.maximum(lo_v - pad_v, 0.0), np.minimum(hi_v + pad_v, 1.0)], axis=1)
    area = (window[:, 1] - window[:, 0]) * (window[:, 3] - window[:, 2])
    ok = ~below.reshape(m, -1).all(axis=1) & ~own & (area < WINDOW_MAX)
    return np.where(ok[:, None], window, 0.0)


def ray_square_points(rng: np.random.Generator, window: np.ndarray, k: int
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For m patches' windows (m, 4) (all zero: none) and k rays each: points u, v (m, k) of
    the square and each ray's weight (m, k) (see the module docstring; a row sums to 1)."""
    m = len(window)
    u0, u1, v0, v1 = (window[:, i:i + 1] for i in range(4))
    w1 = (u1 - u0) * (v1 - v0)  # (m, 1)
    k1 = int(EMITTER_SHARE * k) if k >= MIN_SPLIT_RAYS else 0
    split = (w1[:, 0] > 0.0) & (k1 > 0)
    inside = np.zeros((m, k), bool)
    inside[:, :k1] = split[:, None]
    su, sv = stratified(rng, m, k)  # the rest, R2, from a full stratified set ...
    if k1:
        au, av = stratified(rng, m, k1)  # ... or, for split patches, k - k1 of another
        bu, bv = stratified(rng, m, k - k1)
        su[split] = np.concatenate([au, bu], axis=1)[split]
        sv[split] = np.concatenate([av, bv], axis=1)[split]
    u, v = _rest(su, sv, u0, u1, v0, v1)
    u = np.where(inside, u0 + su * (u1 - u0), u)
    v = np.where(inside, v0 + sv * (v1 - v0), v)
    rest = np.where(split, k - k1, k)[:, None]
    weight = np.where(inside, w1 / max(k1, 1), (1.0 - np.where(split[:, None], w1, 0.0)) / rest)
    return u, v, weight


def _rest(s: np.ndarray, t: np.ndarray, u0, u1, v0, v1) -> tuple[np.ndarray, np.ndarray]:
    """Uniform points of the square minus the window [u0, u1] x [v0, v1] from uniform (s, t):
    s runs along its four strips (left, right, below, above) laid end to end by area."""
    width = u1 - u0
    pieces = np.concatenate([u0, 1.0 - u1, width * v0, width * (1.0 - v1)], axis=1)
    ends = np.cumsum(pieces, axis=1)
    x = s * ends[:, 3:4]
    piece = (x[..., None] >= ends[:, None, :3]).sum(axis=2)  # 0..3
    start = np.take_along_axis(np.concatenate([np.zeros_like(u0), ends[:, :3]], axis=1),
                               piece, axis=1)
    frac = (x - start) / np.maximum(np.take_along_axis(pieces, piece, axis=1), 1e-300)
    frac = np.clip(frac, 0.0, 1.0)
    u = np.choose(piece, [frac * u0, u1 + frac * (1.0 - u1), u0 + t * width, u0 + t * width])
    v = np.choose(piece, [t, t, frac * v0, v1 + frac * (1.0 - v1)])
    return u, v
