"""A pixel's shadows on an area light united (`raytrace.exact_soft`): a convex object's whole
shadow as its silhouette's polygon (`occluders.Convex.shadows`, in numba where it loads),
given by its corners where it is a pixel's one shadow (measured with no GEOS:
`regions.minus_convex`); every other pixel's shapes united by GEOS (shapely >= 2, the
optional extra `exact`), snap-rounded to the light's grid.
"""

from __future__ import annotations

import numpy as np

from .arrange import polygonal as _polygonal
from .lightshapes import FramedLight
from .occluders import Objects
from .regions import convex_corners

__all__ = ["FEW_PIECES", "pixel_unions", "shapes_of", "unite", "whole_bodies"]

# Pieces of shadow per pixel that are united pairwise over all pixels at once (more: one
# cascaded union per pixel).
FEW_PIECES = 8


def pixel_unions(shapely, bodies: tuple, shapes: list, owner: list, n: int, grid: float,
                 flat: bool, arranged: np.ndarray) -> tuple[np.ndarray, tuple]:
    """`unite` of the whole bodies' shadows (`whole_bodies`' three), first, and the shapes
    (arrays) of the owners (arrays of pixels) of n pixels: (the union (n,) object; (one
    (n,): where a pixel's union is one convex polygon, its row in corners (s, k, 2) and
    counts (s,); -1 elsewhere)).  With `flat` (the caller measures those rows), a pixel whose
    one shadow is a whole body's is left out of the union (None) and given by its corners
    only, no GEOS; without, no pixel has a row.  An outline's union (`arranged`) is not
    convex."""
    corners, count, at = bodies
    others = np.bincount(np.concatenate(owner + [np.zeros(0, int)]).astype(np.int64),
                         minlength=n)
    alone = flat & (np.bincount(at, minlength=n)[at] == 1) & (others[at] == 0)
    union, single = unite(shapely, [shapes_of(shapely, corners[~alone], count[~alone])] +
                          shapes, [at[~alone]] + owner, n, grid)
    single[arranged] = False
    shaped = np.flatnonzero(single) if flat else np.zeros(0, int)
    given, sizes = convex_corners(shapely, union[shaped])
    one, k = np.full(n, -1), int(alone.sum())
    one[at[alone]] = np.arange(k)
    one[shaped] = k + np.arange(len(shaped))
    rows = np.zeros((k + len(shaped), max(corners.shape[1], given.shape[1]), 2))
    rows[:k, :corners.shape[1]] = corners[alone]
    rows[k:, :given.shape[1]] = given
    return union, (one, rows, np.r_[count[alone], sizes])


def whole_bodies(light: FramedLight, objects: Objects, p: np.ndarray, meet: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The shadows of convex objects wholly between p's parallel plane and the light's
    (0 <= h < h(p), h the height over the light's plane toward p): p is outside such an
    object and its whole shadow is the pyramid's part of it, the polygon of its silhouette's
    corners' shadows (`occluders.Convex.shadows`).  Returns (corners (w, k, 2), counts (w,),
    their pixels (w,)), those of 3 corners or more; their clusters are taken out of `meet`
    (n, C) for those p."""
    got = [(np.zeros((0, 1, 2)), np.zeros(0, np.int64), np.zeros(0, int))]
    height = (p - light.center) @ light.normal
    for j, body in enumerate(objects.bodies):
        if body is None:
            continue
        clusters = objects.owner == j
        h = (body.points - light.center) @ light.normal
        whole = meet[:, clusters].any(axis=1) & (h.min() >= 0) & (h.max() < height)
        at = np.flatnonzero(whole)
        if len(at) == 0:
            continue
        flat, count = body.shadows(p[at], light)
        got.append((flat[count >= 3], count[count >= 3], at[count >= 3]))
        meet[np.ix_(at, clusters)] = False
    out = np.zeros((sum(len(g[1]) for g in got), max(g[0].shape[1] for g in got), 2))
    start = 0
    for flat, _, _ in got:
        out[start:start + len(flat), :flat.shape[1]] = flat
        start += len(flat)
    return out, np.concatenate([g[1] for g in got]), np.concatenate([g[2] for g in got])


def unite(shapely, shapes: list, owner: list, n: int, grid: float
          ) -> tuple[np.ndarray, np.ndarray]:
    """(n,) object array: per pixel the union of the shapes (arrays) whose owners (arrays of
    pixel indices) name it, snap-rounded to `grid`, None where none; and (n,) bool, the pixels
    with one shape (convex, as every shape here is)."""
    out, single = np.full(n, None, object), np.zeros(n, bool)
    if not shapes:
        return out, single
    shapes, owner = np.concatenate(shapes), np.concatenate(owner)
    order = np.argsort(owner, kind="stable")
    shapes, owner = shapes[order], owner[order]
    real = (shapes != None)  # noqa: E711 (an object array)
    # polygons only: a hull of collinear corners (a body seen edge-on) is a line, no area
    real[real] = ~shapely.is_empty(shapes[real]) & np.isin(shapely.get_type_id(shapes[real]),
                                                           (3, 6))
    shapes, owner = shapes[real], owner[real]
    if len(owner) == 0:
        return out, single
    starts = np.flatnonzero(np.r_[True, owner[1:] != owner[:-1]])
    sizes = np.diff(np.r_[starts, len(owner)])
    # a few pieces: united rank by rank, all pixels at once; many: GEOS's cascaded union
    few = sizes <= FEW_PIECES
    acc = shapes[starts]
    for rank in range(1, int(sizes[few].max(initial=1))):
        more = np.flatnonzero(few & (sizes > rank))
        acc[more] = _polygonal(shapely, shapely.union(acc[more], shapes[starts[more] + rank],
                                                      grid_size=grid))
    for k in np.flatnonzero(~few):
        acc[k] = _polygonal(shapely, np.array([shapely.union_all(
            shapes[starts[k]:starts[k] + sizes[k]], grid_size=grid)], object))[0]
    out[owner[starts]] = acc
    single[owner[starts[sizes == 1]]] = True
    return out, single


def shapes_of(shapely, flat: np.ndarray, count: np.ndarray) -> np.ndarray:
    """(n,) object array of shapely polygons from corners flat (n, k, 2), count (n,) (an empty
    polygon where fewer than 3)."""
    out = np.full(len(flat), shapely.Polygon(), object)
    ok = np.flatnonzero(count >= 3)
    if len(ok):
        mask = np.arange(flat.shape[1])[None] < count[ok, None]
        coords = flat[ok][mask]
        which = np.repeat(np.arange(len(ok)), count[ok])
        out[ok] = shapely.polygons(shapely.linearrings(coords, indices=which))
    return out
