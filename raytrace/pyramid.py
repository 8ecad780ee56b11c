"""Triangles cut to the pyramid from a point over an area light and carried onto the light's
plane (`raytrace.exact_soft`), float64, vectorised over (pixel, triangle) pairs.

Most candidates lie wholly inside the pyramid or wholly beyond one of its planes: those are
decided from their three corners' signed distances (the same values the clip computes) and
only the triangles that cross a plane are clipped (`polygons.clip`).  A triangle wholly inside
comes out as its own three corners, as the clip would return them; one wholly outside a plane
as nothing, as the clip would leave it.  `uncut`: the whole shadows of triangles between the
light's plane and the point's, for the outline unions of `raytrace.arrange`.
"""

from __future__ import annotations

import numpy as np

from . import polygons
from .lightshapes import FramedLight


def cut(light: FramedLight, corners: np.ndarray, p: np.ndarray, pix: np.ndarray,
        tri: np.ndarray, base: np.ndarray, m: list | None = None, store: bool = True):
    """Triangles tri (q,) cut to the pyramid from p[pix] over `base` (k, 3) (the light's
    plane, then each side plane through p; m: `sides`, computed where not given), not yet
    carried onto the light's plane (`carry` does that for the rows wanted): (pieces (q', k',
    3), count (q',), pix, tri, whole (q',)) of those with something left, in the order given,
    zero past each count; whole where the triangle lies wholly inside (its three corners).
    Without `store`, pieces is None: which pairs keep something, and how much, without the
    pieces' memory (`pieces` makes the rows wanted later, the same floats).  In numba where
    it loads (`raytrace.exactkernels`: the same bytes), else in numpy."""
    m = sides(light, p, base) if m is None else m
    loaded = polygons.kernels()
    if loaded is not None:
        pieces, count, whole, keep = loaded.cut(corners, tri, pix, p, light.center,
                                                 light.normal,
                                                 np.stack(m) if m else np.zeros((0,) + p.shape),
                                                 store)
    else:
        pieces, count, whole = _cut(light, corners, p, pix, tri, m)
        keep = np.flatnonzero(count >= 3)
        pieces, count, whole = pieces[keep], count[keep], whole[keep]
    if not store:
        return None, count, pix[keep], tri[keep], whole
    width = max(3, int(count.max(initial=3)))
    return np.ascontiguousarray(pieces[:, :width]), count, pix[keep], tri[keep], whole


def pieces(light: FramedLight, corners: np.ndarray, p: np.ndarray, pix: np.ndarray,
           tri: np.ndarray, m: list, width: int) -> np.ndarray:
    """(q, width, 3): `cut`'s pieces of the pairs pix, tri (q,), every one of which keeps
    something (`cut(store=False)` said so), zero past each count."""
    got = cut(light, corners, p, pix, tri, None, m)[0]
    out = np.zeros((len(tri), width, 3))
    out[:, :got.shape[1]] = got
    return out


def _cut(light: FramedLight, corners: np.ndarray, p: np.ndarray, pix: np.ndarray,
         tri: np.ndarray, m: list) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`exactkernels.cut` in numpy: (pieces (q, k', 3) zero past each count, count (q,), whole
    (q,)) of every pair, count 0 where nothing is left."""
    poly = corners[tri]
    dist = polygons.dot(poly - light.center, light.normal)                   # (q, 3) per plane
    out, whole = _beyond(dist)
    # plane by plane, only the triangles no plane has put wholly outside yet
    live = np.flatnonzero(~out)
    rel = poly[live] - p[pix[live]][:, None]
    for side in m:
        beyond, inside = _beyond(polygons.dot(rel, side[pix[live]][:, None]))
        out[live] = beyond
        whole[live] &= inside
        live, rel = live[~beyond], rel[~beyond]
    whole &= ~out
    count = np.where(whole, 3, 0)
    crossing = np.flatnonzero(~out & ~whole)
    piece, n = _clip(light, poly[crossing], p, pix[crossing], m)
    width = max(3, piece.shape[1])
    pieces = np.zeros((len(tri), width, 3))
    pieces[whole, :3] = poly[whole]
    pieces[crossing, :piece.shape[1]] = piece
    count[crossing] = n
    pieces[np.arange(width)[None] >= count[:, None]] = 0.0
    return pieces, count, whole


def carry(light: FramedLight, p: np.ndarray, pieces: np.ndarray, pix: np.ndarray,
          whole: np.ndarray) -> np.ndarray:
    """(q, k, 2): `cut`'s pieces (q, k, 3) of the pairs seen from p[pix] (q,) carried onto the
    light's plane, as one carrying of every piece would give them (row by row the same
    floats); a whole triangle's slots past its three corners are zero."""
    flat = polygons.project(pieces, p[pix], light.center, light.normal, light.axes)
    flat[whole, 3:] = 0.0
    return flat


def _beyond(dist: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per triangle, from its corners' signed distances (q, 3): (every corner below the
    plane, every corner on or above it), three columns compared (no (q, 3) reduction)."""
    a, b, c = dist[:, 0], dist[:, 1], dist[:, 2]
    return (a < 0) & (b < 0) & (c < 0), (a >= 0) & (b >= 0) & (c >= 0)


def _clip(light: FramedLight, triangles: np.ndarray, p: np.ndarray, pix: np.ndarray,
          m: list) -> tuple[np.ndarray, np.ndarray]:
    """The clip of `cut` of triangles (q, 3, 3) seen from p[pix] by the light's plane, then
    the side planes m (their inward normals (n, 3) each): (poly (q, k, 3), count (q,)),
    every row kept (count 0 where nothing is left)."""
    poly = triangles.copy()
    count = np.full(len(poly), 3)
    poly, count = polygons.clip(poly, count, polygons.dot(poly - light.center, light.normal))
    for side in m:
        poly, count = polygons.clip(poly, count,
                                    polygons.dot(poly - p[pix][:, None], side[pix][:, None]))
    return poly, count


def sides(light: FramedLight, p: np.ndarray, base: np.ndarray) -> list:
    """Per side plane of the pyramid from each p (n, 3) over `base` (k, 3): its normal (n, 3)
    (not unit), pointing inward (toward the light's centre)."""
    out = []
    for j in range(len(base)):
        m = np.cross(base[j] - p, base[(j + 1) % len(base)] - p)      # (n, 3)
        sign = np.sign(((light.center - p) * m).sum(axis=1))
        out.append(m * sign[:, None])
    return out


# An uncut shadow is used where its corners lie within this many times the light's extent of
# its centre: the snap-rounding grid (`lightshapes.OVERLAY_GRID`, 2^-44 of the extent) then
# still leaves 2^3 spare bits of a float64's 53.
UNCUT_REACH = 2.0 ** 6


def uncut(light: FramedLight, corners: np.ndarray, p: np.ndarray, pix: np.ndarray,
          tri: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The whole shadows of triangles tri (q,) from p[pix] on the light's plane, not cut to
    the pyramid: (flat (q, 3, 2), free (q,) bool).  free where every corner lies on or beyond
    the light's plane's emitting side and strictly nearer to it than p (so the carrying from
    p is a projective map of the slab between: straight edges stay straight, the triangle's
    shadow is the triangle of its corners' shadows, and its part in the pyramid is its shadow
    cut to the light's convex outline) and within UNCUT_REACH of the light."""
    top = polygons.dot(p - light.center, light.normal)
    reach = UNCUT_REACH * np.abs(light.hull).max()
    loaded = polygons.kernels()
    if loaded is not None:
        return loaded.uncut(corners, tri, pix, p, top, light.center, light.normal,
                             light.axes, reach)
    poly = corners[tri]
    height = polygons.dot(poly - light.center, light.normal)                      # (q, 3)
    free = (height >= 0).all(axis=1) & (height < top[pix][:, None]).all(axis=1)
    flat = np.zeros((len(tri), 3, 2))
    flat[free] = polygons.project(poly[free], p[pix[free]], light.center, light.normal,
                                  light.axes)
    free &= (np.abs(flat) <= reach).all(axis=(1, 2))
    return flat, free
