"""The measures of the visible regions of `raytrace.exact_soft`: closed rings in the light's
plane coordinates, measured by `raytrace.polygons` (area, Lambert's irradiance and, asked for,
the unattenuated cosine measure); a convex polygon less one convex polygon in numpy; shapely
regions' rings, holes subtracted."""

from __future__ import annotations

import numpy as np

from . import polygons
from .lightshapes import FramedLight

__all__ = ["closed_rings", "convex_corners", "inside", "measure", "minus_convex",
           "ring_measures"]


def minus_convex(light: FramedLight, cut: np.ndarray, count: np.ndarray, inner: np.ndarray,
                 inner_count: np.ndarray, p: np.ndarray, normal: np.ndarray,
                 direct: bool = False) -> tuple[np.ndarray, ...]:
    """(n,) area and irradiance of the convex polygons cut (n, k, 2), count (n,) (counter-
    clockwise, as `exact_soft` cuts the light's box) less one convex polygon each, inner
    (n, m, 2), inner_count (n,) (`convex_corners`): the measure of cut less that of inner
    clipped by each of cut's edges (no GEOS)."""
    whole = ring_measures(light, *closed_rings(cut, count), p, normal, direct)
    inner, inner_count = inside(cut, count, inner, inner_count)
    part = ring_measures(light, *closed_rings(inner, inner_count), p, normal, direct)
    return tuple(w - q for w, q in zip(whole, part))


def convex_corners(shapely, pieces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The corners of convex polygons `pieces` (n,) (shapely) as their exterior rings hold
    them, each row's last repeated to the widest's: (corners (n, m, 2), counts (n,), 0 where
    fewer than 3)."""
    if len(pieces) == 0:
        return np.zeros((0, 1, 2)), np.zeros(0, np.int64)
    coords, which = shapely.get_coordinates(shapely.get_exterior_ring(pieces),
                                            return_index=True)
    m = np.bincount(which, minlength=len(pieces)) - 1        # corners (the closing one repeats)
    first = np.r_[0, np.cumsum(m + 1)[:-1]]
    inner = coords[first[:, None] + np.minimum(np.arange(m.max()), m[:, None] - 1)]
    return inner, np.where(m >= 3, m, 0)


def inside(cut: np.ndarray, count: np.ndarray, inner: np.ndarray, inner_count: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray]:
    """Convex polygons inner (n, m, 2), inner_count (n,) clipped by each edge of the convex
    counter-clockwise polygons cut (n, k, 2), count (n,): (corners, counts).  In numba where
    it loads (`raytrace.exactkernels.inside`: the same corners, zero past each count)."""
    loaded = polygons.kernels()
    if loaded is not None:
        inner, inner_count = loaded.inside(cut, count, inner, inner_count)
        return inner[:, :max(int(inner_count.max(initial=0)), 1)], inner_count
    for e in range(cut.shape[1]):
        start = cut[:, e]
        edge = cut[np.arange(len(cut)), (e + 1) % np.maximum(count, 1)] - start
        d = (edge[:, None, 0] * (inner[..., 1] - start[:, None, 1])
             - edge[:, None, 1] * (inner[..., 0] - start[:, None, 0]))
        d = np.where((e < count)[:, None], d, 1.0)           # past the cut's last edge: keep
        inner, inner_count = polygons.clip(inner, inner_count, d)
    return inner, inner_count


def closed_rings(flat: np.ndarray, count: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Polygons flat (n, k, 2) with count (n,) corners as closed rings: coords (c, 2) (each
    ring's first corner again at its end) and ring (c,) the row of each."""
    n, k, _ = flat.shape
    at = np.arange(k + 1)[None]
    use = at <= count[:, None]
    index = np.where(at == count[:, None], 0, np.minimum(at, k - 1))
    coords = np.take_along_axis(flat, index[..., None], 1)[use]
    return coords, np.broadcast_to(np.arange(n)[:, None], use.shape)[use]


def ring_measures(light: FramedLight, coords: np.ndarray, ring: np.ndarray, p: np.ndarray,
                  normal: np.ndarray, direct: bool = False) -> tuple[np.ndarray, ...]:
    """|area| and |irradiance| (rings,) of closed rings (`polygons.ring_measures`; a disk's
    part inside them for a disk light), ring r seen from p[r] with normal[r]."""
    args = (coords, ring, len(p))
    if light.radius is None:
        return polygons.ring_measures(*args, p, normal, light.center, light.axes, direct)
    return polygons.disk_ring_measures(*args, light.radius, p, normal, light.center,
                                       light.axes, direct)


def measure(shapely, light: FramedLight, seen: np.ndarray, p: np.ndarray, normal: np.ndarray,
            direct: bool = False) -> tuple[np.ndarray, ...]:
    """(n,) area and irradiance of the regions `seen` (n,) seen from p (n, 3) with normals."""
    parts, part_of = shapely.get_parts(seen, return_index=True)
    rings, ring_of = shapely.get_rings(parts, return_index=True)
    n = len(seen)
    if len(rings) == 0:
        return tuple(np.zeros(n) for _ in range(3 if direct else 2))
    # the first ring of each part is its outside, the others its holes
    sign = np.where(np.r_[True, ring_of[1:] != ring_of[:-1]], 1.0, -1.0)
    coords, which = shapely.get_coordinates(rings, return_index=True)
    owner = part_of[ring_of]
    got = ring_measures(light, coords, which, p[owner], normal[owner], direct)
    return tuple(np.bincount(owner, sign * m, n) for m in got)
