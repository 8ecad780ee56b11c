"""The union of many small shadows of one pixel by its outline alone (`raytrace.exact_soft`).

A triangle wholly between the light's plane and p's parallel plane is taken whole, its shadow
not cut to the pyramid (`pyramid.uncut`): inside the light's convex outline that is the same
region, and the union is only ever taken away from the light.  Where two such shadows share
an edge (the same two welded corners) and lie on its two sides (each ring turned counter-
clockwise, they run it in opposite directions), every point near that edge's inside is
covered: the edge is not on the union's boundary.  What is left (the other edges of those
shadows, and every edge of a cut shadow) holds the whole boundary of the union: GEOS nodes
it in float64 (floating noding; where its result is not simple, two segments crossing a
rounding apart, the snap-rounding noder on the light's grid, `lightshapes.OVERLAY_GRID`, to
which the union is snapped anyway where it is next united or taken away, as every other
boolean here), and polygonizes it into faces that the boundary does not cross, so each face is
wholly inside the union or wholly outside: the faces whose interior point meets a piece of
some area (closed: a point on an edge left out is inside both of its shadows) are the union,
which GEOS's coverage union joins.  The same region as the pieces' union (up to the roundings
and to slivers of a rounding between shadows of one corner), from a few hundred edges
instead of a cascade of thousands of overlays.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np

from . import pyramid
from .backends import cpu_threads
from .lightshapes import FramedLight

# Threads for the crowded pixels' unions (None: one per core; GEOS, through shapely, releases
# the GIL).
THREADS = None


def unions(shapely, light: FramedLight, corners: np.ndarray, p: np.ndarray, flat: np.ndarray,
           count: np.ndarray, pix: np.ndarray, tri: np.ndarray, heavy: np.ndarray,
           welded: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The union (`union`) of the shadows of each pixel among the pairs `heavy` of triangles
    tri seen from p[pix], cut (flat, count: `pyramid.cut`), welded (M, 3) the scene's corner
    indices: (unions (g,) object, their pixels (g,))."""
    heavy = heavy[np.argsort(pix[heavy], kind="stable")]
    loose, free = pyramid.uncut(light, corners, p, pix[heavy], tri[heavy])
    box = np.stack([light.hull.min(axis=0), light.hull.max(axis=0)])
    starts = np.flatnonzero(np.r_[True, pix[heavy][1:] != pix[heavy][:-1]])
    ends = np.r_[starts[1:], len(heavy)]

    def one(k: int):
        q, at = heavy[starts[k]:ends[k]], slice(starts[k], ends[k])
        return union(shapely, flat[q], count[q], loose[at], free[at], welded[tri[q]], box,
                     light.grid)

    threads = min(THREADS or cpu_threads(), len(starts))
    united = np.empty(len(starts), object)
    if threads <= 1:
        united[:] = [one(k) for k in range(len(starts))]
    else:
        with ThreadPoolExecutor(threads) as pool:
            united[:] = list(pool.map(one, range(len(starts))))
    return polygonal(shapely, united), pix[heavy[starts]]


def union(shapely, flat: np.ndarray, count: np.ndarray, uncut: np.ndarray, free: np.ndarray,
          ids: np.ndarray, box: np.ndarray, grid: float):
    """The union (a shapely geometry) of the shadows of one pixel's triangles: cut to the
    pyramid, corners flat (q, k, 2), count (q,); where free (q,) their whole shadows uncut
    (q, 3, 2) instead (`pyramid.uncut`: the same inside the light's outline, and only that
    part is ever used), ids (q, 3) their welded corners' indices (noded in float64: the
    module); box (2, 2): the corners of a rectangle that holds the light (the union's part
    there is exact; outside, it is cut to it); grid: the light's snap-rounding grid, for
    an arrangement the floating noder leaves unnoded."""
    polys = np.empty(len(flat), object)
    polys[free] = shapely.polygons(uncut[free])
    cut = np.flatnonzero(~free)
    if len(cut):
        mask = np.arange(flat.shape[1])[None] < count[cut, None]
        polys[cut] = shapely.polygons(shapely.linearrings(
            flat[cut][mask], indices=np.repeat(np.arange(len(cut)), count[cut])))
    start, end, key_a, key_b = edges(uncut, ids, free)
    big = int(max(key_a.max(initial=0), key_b.max(initial=0))) + 1
    inner = np.isin(key_a * big + key_b, key_b * big + key_a)
    lines = [shapely.linestrings(np.stack([start[~inner], end[~inner]], axis=1))]
    other = np.flatnonzero(~free)
    if len(other):
        lines.append(shapely.boundary(polys[other]))
    # only the union's part in the light's box is ever used: the edges cut to it, its outline
    # added (so the faces inside close)
    frame = shapely.box(*box[0], *box[1])
    lines = shapely.clip_by_rect(shapely.multilinestrings(
        shapely.get_parts(np.concatenate(lines))), *box[0], *box[1])
    # noded in float64 by GEOS's robust overlay (floating noding): a quarter of the snap-
    # rounding noder's time on a few hundred edges.  Its result can still hold two segments
    # that cross a rounding apart (seen: a face of 5 % of the light lost by the polygonizer
    # as a cut edge); then, and only then (`is_simple`, exact), the snap-rounding noder on
    # the light's grid, whose output is always noded; the union is snapped to that grid
    # where it is next united or taken away anyway
    noded = shapely.union_all([lines, shapely.boundary(frame)])
    if not shapely.is_simple(noded):
        noded = shapely.union_all([lines, shapely.boundary(frame)], grid_size=grid)
    faces = shapely.get_parts(shapely.polygonize(shapely.get_parts(noded)))
    if len(faces) == 0:
        return shapely.Polygon()
    tree = shapely.STRtree(polys[shapely.area(polys) > 0])   # no area: no cover
    inside = np.unique(tree.query(shapely.point_on_surface(faces), predicate="intersects")[0])
    return shapely.coverage_union_all(faces[inside])


def edges(uncut: np.ndarray, ids: np.ndarray, free: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The edges of the free whole shadows uncut (q, 3, 2) of some area, each turned counter-
    clockwise: (start (e, 2), end (e, 2), their welded corner ids (e,), (e,))."""
    tri = uncut[:, :3]
    signed = (tri[:, 1, 0] - tri[:, 0, 0]) * (tri[:, 2, 1] - tri[:, 0, 1]) - \
        (tri[:, 1, 1] - tri[:, 0, 1]) * (tri[:, 2, 0] - tri[:, 0, 0])
    at = np.flatnonzero(free & (signed != 0))
    turn = signed[at] < 0
    # edge e of every shadow, then e + 1: from corner e to e + 1, or back where turned
    e = np.arange(3)[:, None]
    s0, s1 = np.where(turn, (e + 1) % 3, e), np.where(turn, e, (e + 1) % 3)
    return (uncut[at, s0].reshape(-1, 2), uncut[at, s1].reshape(-1, 2), ids[at, s0].reshape(-1),
            ids[at, s1].reshape(-1))


def polygonal(shapely, geoms: np.ndarray) -> np.ndarray:
    """geoms (n,) with the parts of no area of any geometry collection among them dropped (an
    overlay that snaps a sliver to its grid may return the collapsed sliver as a line)."""
    mixed = np.flatnonzero(shapely.get_type_id(geoms) == 7)
    for k in mixed:
        parts = shapely.get_parts(shapely.get_parts(geoms[k]))   # multipolygons in it too
        geoms[k] = shapely.multipolygons(parts[shapely.get_type_id(parts) == 3])
    return geoms
