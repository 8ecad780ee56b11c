"""Exact visibility of polygonal and disk lights: the visible part of the light, computed.

For light i and a pixel's visible point p (float64: the pixel-centre ray met with its visible
triangle's plane, as `depth` is), the visible region is the light's shape, cut to where p's
camera-facing normal n sees it (n . (x - p) > 0), less the union of every triangle's shadow
on it: the triangle cut to the pyramid from p over the light (its side planes and the light's
plane) and carried from p onto the light's plane.  Both sides of a triangle occlude; only p's
own triangle and those coplanar with it (`candidates.COPLANAR_RELATIVE`) are left out.  Then

    visibility_exact = area(visible) / area(light)
    irradiance_exact = Lambert's formula over the visible region's rings (unit radiance),

0 for both where p is not on the light's emitting side.  docs/CONVENTIONS.md ("Area lights:
exact visibility") says what is exact at a contact and at a tie.

Candidates come from a conservative query, never from sampled rays (`raytrace.candidates`):
clusters of triangles whose bounding spheres are inside every plane of the pyramid and whose
boxes meet its box, then triangles whose boxes do, then the cut itself.  A closed, convex,
consistently wound object (a box, a sphere's tessellation) shadows p from outside as one
convex polygon (the shadow of a convex body from a point outside it is convex): the polygon of
its silhouette's corners' shadows where it lies wholly between p and the light, else the hull
of its cut triangles' shadows; and not at all from its own outside.  Every other object's
triangles are united: under a rect or disk light, a pixel's more than WINDING_PIECES shadows,
where those are all its shadows and all but a few (`windings.LOOSE`, at a contact) are free,
measured from their outline's winding numbers with no polygon boolean (`raytrace.windings`),
the few taken away by inclusion and exclusion (`raytrace.windmeasures`); else a pixel's union
of more than MANY_PIECES from its outline alone (`raytrace.arrange`).  Under a rect or disk
light, with the `fast` extra's kernels, a block of pixels (BLOCK a side, more in a finer
frame: `block_side`) first counts once the outline of the triangles each of its points sees
turned one way, and each of its pixels adds its own pairs of the others
(`raytrace.blockwindings`).  One convex shadow on a rect or disk
is taken away in numpy (clipped edge by edge), a convex object's whole shadow given by its
corners alone, no GEOS (in numba where it loads: `occluders.Convex.shadows`); several are
united, and taken away, by GEOS (shapely >= 2, the optional extra `exact`), snap-rounded
(`lightshapes.OVERLAY_GRID`; `raytrace.unions`); the measures are `raytrace.polygons`'.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import numpy as np

from shadowvol.frame import EXACT_OUTPUTS
from shadowvol.scene import AreaLight, DirectionalLight, Scene

from . import arrange, blockwindings, candidates, polygons, pyramid, windings, windmeasures
from .arrange import polygonal as _polygonal
from .regions import closed_rings as _closed_rings
from .regions import measure as _measure
from .regions import minus_convex as _minus_convex
from .regions import ring_measures as _ring_measures
from .backends import for_each_tile
from .camera import RayGrid
from .lightshapes import FramedLight, frame_light, shapely_module
from .masks import MaskTracer, _primary_hits, scene_backend, shadow_masks
from .occluders import CONVEX_RELATIVE, Objects, weld
from .occluders import objects as _objects
from .switches import casting, receiving_objects
from .unions import pixel_unions, shapes_of, whole_bodies

__all__ = ["EXACT_OUTPUTS", "ExactVisibility", "check_exact", "exact_visibility",
           "visible_regions"]

# Pieces of shadow of one pixel above which their union is measured from its outline's
# windings where it can be (`raytrace.windings`): from 9 on, the bunny 64x64 0.95x and the
# blob 48x48 0.88x the CPU of from 17 (MANY_PIECES + 1).
WINDING_PIECES = 8
# Pieces of shadow of one pixel above which their union is taken from its outline
# (`raytrace.arrange`) rather than by GEOS's cascaded union.
MANY_PIECES = 16
# Pixels a side of the blocks of the image whose pixels share their steady triangles' outline
# (`raytrace.blockwindings`; 0: none, every pixel its own pairs), one more where a pixel's
# footprint seen from the light's centre is under each of FINE (`block_side`): a larger block
# shares its outline among more pixels, and its pixels' own pairs grow with the distance
# between its points.  The bunny's CPU with blocks of 3 against 2 (chunks of whole blocks,
# `_chunks`): 1.10x at 64x64 (footprint 0.013), 1.05x at 128x128 (0.0066), 0.92x at 192x192
# (0.0044) and 256x256 (0.0033); of 4 against 2 at 512x512 (0.0017) 0.81x, of 3 0.86x.
BLOCK = 2
FINE = (1 / 200, 1 / 400)
# Rows of the frame whose primary hits give the footprint (`block_side`), evenly spaced.
FOOTPRINT_ROWS = 16
# Pixels per chunk (each chunk's candidate arrays are pixels x clusters; whole bands of a
# block's rows, `_chunks`).
CHUNK_PIXELS = 2048
# Pixels per tile at most (whole blocks of rows; a pixel costs ~1,000x a masks' ray).  A
# frame is cut into TILES_PER_THREAD tiles a thread of TILE_PIXELS_LEAST pixels or more, one
# a thread at least: its penumbra lies in a few rows, so halves left a thread idle (the bunny
# 128x128: wall 570 -> 356 ms in eight tiles, the CPU the same; a tile costs ~2 ms of CPU,
# so a small frame keeps fewer: the bunny 32x32 in eight took 10 % more CPU, 9 % less wall).
EXACT_TILE_PIXELS = 1 << 15
TILES_PER_THREAD = 4
TILE_PIXELS_LEAST = 1024


class ExactVisibility(NamedTuple):
    """visibility (L, H, W) float64 and irradiance (L, H, W) float64 (see the module); direct
    (L, H, W) float64 with `exact_visibility(direct=True)`, else None: the integral over the
    visible region of cos(at p) cos(at the light) dA over the light's area, the limit of the
    renderers' sampled shading (no fall-off: docs/CONVENTIONS.md); for a hard light, as
    irradiance."""

    visibility: np.ndarray
    irradiance: np.ndarray
    direct: np.ndarray | None = None


def check_exact(scene: Scene) -> None:
    """SceneError for a light with no exact visibility (a sphere), MissingExtra without
    shapely where an area light needs it: what `exact_visibility` would refuse, before any
    work."""
    for i, light in enumerate(scene.lights):
        if isinstance(light, AreaLight):
            frame_light(light, np.zeros(3), f"lights[{i}]")
            shapely_module()


def visible_regions(scene: Scene, light_index: int, backend: str | MaskTracer = "embree"
                    ) -> tuple[np.ndarray, "FramedLight"]:
    """(H, W) object array: the visible region of area light `light_index` at each pixel (a
    shapely geometry in the light's plane coordinates, `FramedLight.axes` about its centre; None
    where nothing is covered or the point is behind the light), and the light in the frame.
    For tests and pictures; `exact_visibility` measures the same regions."""
    regions = np.full(scene.height * scene.width, None, object)
    exact_visibility(scene, backend, _regions=(light_index, regions))
    mt = scene_backend(scene, backend) if isinstance(backend, str) else backend
    return regions.reshape(scene.height, scene.width), frame_light(
        scene.lights[light_index], mt.origin, f"lights[{light_index}]")


def exact_visibility(scene: Scene, backend: str | MaskTracer = "embree",
                     _regions=None, direct: bool = False) -> ExactVisibility:
    """`visibility_exact` and `irradiance_exact` of every light of `scene` (module docstring):
    (L, H, W) float64 each.  A point, spot or directional light: 1 where `lit`, and
    irradiance n . l there (a unit light without fall-off, as the renderers shade one).
    SceneError for a sphere light."""
    mt = scene_backend(scene, backend) if isinstance(backend, str) else backend
    tracer, triangles, origin = mt
    H, W, L = scene.height, scene.width, len(scene.lights)
    lights = [None if not isinstance(lt, AreaLight) else
              frame_light(lt, origin, f"lights[{i}]") for i, lt in enumerate(scene.lights)]
    shapely = shapely_module() if any(lights) else None
    vis = np.zeros((L, H * W))
    irr = np.zeros((L, H * W))
    unatt = np.zeros((L, H * W)) if direct else None
    corners = tracer.vertices[tracer.faces].astype(np.float64, copy=False)
    ids = scene.triangles()[2]
    # corners welded by their coordinates: the distinct vertices' indices
    welded = weld(tracer.vertices)[tracer.faces]
    objects = _objects(corners, ids, casting(scene), welded) if any(lights) else None
    # per triangle: its object receives shadows (docs/CONVENTIONS.md, "Shadow switches")
    receives = receiving_objects(scene)[ids] if len(ids) else np.zeros(0, bool)
    camera = dataclasses.replace(scene.camera, eye=scene.camera.eye - origin,
                                 target=scene.camera.target - origin)
    grids = (RayGrid(camera, W, H, np.float32), RayGrid(camera, W, H, np.float64))
    reach = np.inf if camera.eye.any() else grids[1].farthest_start()   # `blockwindings`
    pairs = neighbours(tracer, triangles, grids, H) if BLOCK > 0 and any(lights) else None
    blocks = [0 if lt is None else block_side(lt, pairs) for lt in lights]
    # a tile a thread at least, TILES_PER_THREAD where each keeps TILE_PIXELS_LEAST pixels;
    # whole blocks of pixels (every light's block's rows) in each
    threads = max(1, getattr(tracer, "threads", 1))
    per = TILES_PER_THREAD if threads > 1 else 1
    rows_per_tile = max(1, min(EXACT_TILE_PIXELS // W, -(-H // threads),
                               max(-(-H // (threads * per)), -(-TILE_PIXELS_LEAST // W))))
    unit = int(np.lcm.reduce([b for b in blocks if b > 0] or [1]))
    rows_per_tile = -(-rows_per_tile // unit) * unit
    tiles = [slice(y, min(y + rows_per_tile, H)) for y in range(0, H, rows_per_tile)]
    hard = [i for i, lt in enumerate(lights) if lt is None]
    lit = shadow_masks(scene.replace(lights=tuple(scene.lights[i] for i in hard)), mt)[0] \
        if hard else None

    # per area light: its corners' heights over its plane (once a frame, not a chunk)
    sides = [None if lt is None or objects is None else candidates.heights(lt, objects, corners)
             for lt in lights]

    def trace_tile(rows: slice) -> None:
        _, index, hit = _primary_hits(tracer, triangles, grids, rows)
        if hit is None:
            return
        pixel = rows.start * W + index
        p = hit.point64.T
        normal = (hit.normal * hit.side).T
        for i, light in enumerate(lights):
            if light is None:
                k = hard.index(i)
                on = lit[k].reshape(-1)[pixel]
                vis[i, pixel] = on
                irr[i, pixel] = on * _hard_cosine(scene.lights[i], p, normal, origin)
                if direct:
                    unatt[i, pixel] = irr[i, pixel]
                continue
            for part in _chunks(pixel, W, blocks[i]):
                keep = None if _regions is None or _regions[0] != i else \
                    np.full(len(p[part]), None, object)
                shadowed = receives[hit.tri[part]] & scene.lights[i].shadows
                got = _area_light(shapely, light, objects, corners, p[part], normal[part],
                                  hit.tri[part], keep, shadowed, direct, sides[i],
                                  (pixel[part], W, reach, blocks[i]))
                if keep is not None:
                    _regions[1][pixel[part]] = keep
                vis[i, pixel[part]], irr[i, pixel[part]] = got[:2]
                if direct:
                    unatt[i, pixel[part]] = got[2]

    for_each_tile(trace_tile, tiles, tracer)
    return ExactVisibility(vis.reshape(L, H, W), irr.reshape(L, H, W),
                           None if unatt is None else unatt.reshape(L, H, W))


def block_side(light: FramedLight, pairs: tuple | None) -> int:
    """The side of the blocks of pixels the block path takes under `light` (`raytrace.
    blockwindings`): BLOCK, one more under each of FINE of the frame's `footprint` from its
    `neighbours` pairs; BLOCK where it is 0 or no two neighbours are covered."""
    if BLOCK <= 0:
        return BLOCK
    seen = footprint(light, pairs)
    return BLOCK + sum(int(seen < f) for f in FINE)


def neighbours(tracer, triangles, grids: tuple, height: int) -> tuple[np.ndarray, np.ndarray]:
    """The points p (k, 3) and their right neighbours' (k, 3) in FOOTPRINT_ROWS rows of the
    frame, evenly spaced (pairs of rows: whole packets), where both are covered: traced once
    a frame, not a tile, so the blocks are the same on any number of threads."""
    got, rows = [], np.linspace(0, height - 1, min(height, FOOTPRINT_ROWS)).astype(int)
    for y in np.unique(np.minimum(rows - rows % 2, max(height - 2, 0))).tolist():
        _, index, hit = _primary_hits(tracer, triangles, grids, slice(y, min(y + 2, height)))
        if hit is None:
            continue
        p = hit.point64.T
        pair = np.flatnonzero(np.diff(index) == 1)
        pair = pair[index[pair] // grids[0].width == index[pair + 1] // grids[0].width]
        got.append((p[pair], p[pair + 1]))
    if not got:
        return np.zeros((0, 3)), np.zeros((0, 3))
    return np.concatenate([a for a, _ in got]), np.concatenate([b for _, b in got])


def footprint(light: FramedLight, pairs: tuple | None) -> float:
    """The median over the `neighbours` pairs of a point's distance from its right
    neighbour's over its distance from the light's centre (inf where there is none)."""
    if pairs is None or len(pairs[0]) == 0:
        return np.inf
    p, q = pairs
    return float(np.median(np.linalg.norm(q - p, axis=1)
                           / np.linalg.norm(p - light.center, axis=1)))


def _chunks(pixel: np.ndarray, width: int, block: int) -> list[slice]:
    """Slices of the tile's covered pixels (ascending indices) of about CHUNK_PIXELS each, cut
    where a band of `block` rows begins (whole blocks: a block cut in two shares its outline
    between fewer pixels), one band at least; CHUNK_PIXELS each where `block` is 0."""
    if block <= 0 or len(pixel) == 0:
        return [slice(a, a + CHUNK_PIXELS) for a in range(0, len(pixel), CHUNK_PIXELS)]
    band = pixel // (width * block)
    starts = np.flatnonzero(np.r_[True, band[1:] != band[:-1]])
    cut = starts[np.r_[True, np.diff(starts // CHUNK_PIXELS) > 0]]
    return [slice(a, b) for a, b in zip(cut.tolist(), np.r_[cut[1:], len(pixel)].tolist())]


def _hard_cosine(light, p: np.ndarray, normal: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """(n,) max(n . l, 0), l the unit direction from p toward a hard light."""
    if isinstance(light, DirectionalLight):
        to = np.broadcast_to(-light.direction, p.shape)
    else:
        to = light.position - origin - p
        to = to / np.linalg.norm(to, axis=1, keepdims=True)
    return np.maximum((normal * to).sum(axis=1), 0.0)


def _area_light(shapely, light: FramedLight, objects: Objects, corners: np.ndarray,
                p: np.ndarray, normal: np.ndarray, own: np.ndarray, regions=None,
                shadowed: np.ndarray | None = None, direct: bool = False,
                sides: tuple | None = None, where: tuple | None = None
                ) -> tuple[np.ndarray, ...]:
    """(n,) visibility and irradiance of `light` at points p (n, 3) with camera-facing unit
    normals (n, 3) on triangles own (n,); `regions` (n,) object array: filled with the
    visible regions (shapely, the light's plane coordinates) where given; `shadowed` (n,)
    bool (default all): the points that receive shadows from this light (the others see the
    light's part on their side whole: the shadow switches); `direct`: the unattenuated
    measure over the light's area too (`ExactVisibility.direct`); `sides`, `where`:
    `_occluded`'s (sides made here where not given)."""
    n = len(p)
    height = (p - light.center) @ light.normal
    front = np.flatnonzero(height > 0)
    out_v, out_e, out_d = np.zeros(n), np.zeros(n), np.zeros(n)
    if len(front) == 0:
        return (out_v, out_e, out_d) if direct else (out_v, out_e)
    p, normal, own = p[front], normal[front], own[front]
    at = np.arange(len(p)) if shadowed is None else np.flatnonzero(shadowed[front])
    sides = candidates.heights(light, objects, corners) if sides is None else sides
    pieces, (one, rows, sizes), chains, loose = _occluded(
        shapely, light, objects, corners, p, normal, own, at, sides,
        None if where is None else (where[0][front], *where[1:]),
        light.outline is None and regions is None)
    # the light cut to p's side: its hull's box cut by n . (x - p) > 0, then the outline
    box = np.array([light.hull.min(axis=0), [light.hull[:, 0].max(), light.hull[:, 1].min()],
                    light.hull.max(axis=0), [light.hull[:, 0].min(), light.hull[:, 1].max()]])
    flat = np.repeat(np.c_[box, np.zeros(4)][None], len(p), axis=0)
    # n . (x - p) at the box's corners x = centre + a u + b v
    dist = ((light.center - p) * normal).sum(axis=1)[:, None] + (box @ (light.axes @ normal.T)).T
    cut, count = polygons.clip(flat, np.full(len(p), 4), dist)
    cut = cut[..., :2]
    area, irr, unatt = np.zeros(len(p)), np.zeros(len(p)), np.zeros(len(p))
    measures = (area, irr, unatt) if direct else (area, irr)
    wound = windings.found(chains)
    has = (pieces != None) | wound  # noqa: E711 (an object array)
    # nothing in the way of a rect or disk: its box cut to p's side, measured as it is
    plain = np.flatnonzero(~has & (one < 0) & (count >= 3)) \
        if light.outline is None and regions is None else np.zeros(0, int)
    if len(plain):
        coords, ring = _closed_rings(cut[plain], count[plain])
        for out, got in zip(measures, _ring_measures(light, coords, ring, p[plain],
                                                     normal[plain], direct)):
            out[plain] = got
    # one convex shadow on a rect or disk: the light less it, in numpy
    lone = np.flatnonzero((one >= 0) & (count >= 3))
    if len(lone):
        for out, got in zip(measures, _minus_convex(light, cut[lone], count[lone],
                                                    rows[one[lone]], sizes[one[lone]], p[lone],
                                                    normal[lone], direct)):
            out[lone] = got
    wound = np.flatnonzero(wound & (count >= 3))
    if len(wound):
        for out, got in zip(measures, windmeasures.measures(light, cut[wound], count[wound],
                                                        chains[wound], p[wound],
                                                        normal[wound], direct, loose[wound])):
            out[wound] = got
    rest = np.setdiff1d(np.arange(len(p)), np.r_[plain, lone, wound])
    if len(rest):
        seen = shapes_of(shapely, cut[rest], count[rest])
        if light.outline is not None:  # a polygon light: its own outline
            seen = _polygonal(shapely, shapely.intersection(seen, shapely.Polygon(light.outline),
                                                            grid_size=light.grid))
        hit = np.flatnonzero(has[rest])
        seen[hit] = _polygonal(shapely, shapely.difference(seen[hit], pieces[rest[hit]],
                                                            grid_size=light.grid))
        for out, got in zip(measures, _measure(shapely, light, seen, p[rest], normal[rest],
                                               direct)):
            out[rest] = got
        if regions is not None:
            regions[front[rest]] = seen
    # the subtractions leave roundings of ~1e-14 either side of 0 and 1
    out_v[front] = np.clip(area / light.area, 0.0, 1.0)
    out_e[front] = np.maximum(irr, 0.0)
    if not direct:
        return out_v, out_e
    out_d[front] = np.maximum(unatt / light.area, 0.0)
    return out_v, out_e, out_d


def _occluded(shapely, light: FramedLight, objects: Objects, corners: np.ndarray,
              p: np.ndarray, normal: np.ndarray, own: np.ndarray, at: np.ndarray, sides: tuple,
              where: tuple | None, outlines: bool) -> tuple[np.ndarray, ...]:
    """The union of the shadows on the light of the points at (indices into p (n, 3), with
    normals and own triangles (n,)) as `_shadows` gives it (n,) each (None, -1 past at),
    its crowded pixels' windings a block at a time first (`raytrace.blockwindings`) where
    `where` (pixels (n,), width, `chains`' eye, its blocks' side: `block_side`, 0 none) and
    `outlines`; sides: `candidates.heights`."""
    base = light.center + light.hull @ light.axes                 # (k, 3)
    pieces, one = np.full(len(p), None, object), np.full(len(p), -1)
    hulls = (one, np.zeros((0, 1, 2)), np.zeros(0, np.int64))
    chains, loose = np.full(len(p), None, object), np.full(len(p), None, object)
    if len(at) == 0 or len(objects.members) == 0:
        return pieces, hulls, chains, loose
    among = None
    if where is not None and outlines and where[3] > 0:
        chains[at], loose[at], met = blockwindings.chains(
            light, objects, corners, sides[2:], p[at], own[at], where[0][at], where[1],
            where[3], WINDING_PIECES, where[2])
        done = windings.found(chains[at])
        # nothing inside the light's box and no shadow apart: the light measured whole, as a
        # pixel of no shadow
        empty = at[done][[len(c) == 0 and k is None for c, k in zip(chains[at[done]],
                                                                    loose[at[done]])]]
        chains[empty] = None
        # the clusters that meet each pixel's block: no other can meet its pyramid
        among = None if met is None else met[0][met[1][~done]]
        at = at[~done]
    if len(at):
        pieces[at], (mine, rows, sizes), chains[at], loose[at] = _shadows(
            shapely, light, objects, corners, p[at], normal[at], own[at], base, sides[1],
            outlines, among)
        one[at] = mine
        hulls = (one, rows, sizes)
    return pieces, hulls, chains, loose


def _shadows(shapely, light: FramedLight, objects: Objects, corners: np.ndarray, p: np.ndarray,
             normal: np.ndarray, own: np.ndarray, base: np.ndarray, clear: np.ndarray,
             outlines: bool = False, among: np.ndarray | None = None
             ) -> tuple[np.ndarray, tuple, np.ndarray, np.ndarray]:
    """(n,) object array: the union of every triangle's shadow on the light's plane seen from
    each p (None where none falls inside the pyramid over `base` (k, 3), or where it is
    given by its corners only); where that is one convex polygon, its corners
    (`unions.pixel_unions`' second; with `outlines` only); with `outlines`, the union's
    boundary from its outline's windings (`raytrace.windings`) where that is certain (the
    union None there), and the few shadows that outline leaves out
    (`windmeasures.measures`' loose; None where none); clear: `candidates.heights`' second;
    among: `candidates.meets`'."""
    lo = np.minimum(p, base.min(axis=0))
    hi = np.maximum(p, base.max(axis=0))
    meet = candidates.meets(light, objects, p, base, lo, hi, among)
    bodies = whole_bodies(light, objects, p, meet)
    shapes, owner = [], []
    pix, tri = candidates.pairs(objects, corners, p, normal, own, meet, lo, hi, clear)
    m = pyramid.sides(light, p, base)
    _, count, pix, tri, whole = pyramid.cut(light, corners, p, pix, tri, base, m, store=False)
    width = max(3, int(count.max(initial=3)))

    def carry(rows):
        pieces = pyramid.pieces(light, corners, p, pix[rows], tri[rows], m, width)
        return pyramid.carry(light, p, pieces, pix[rows], whole[rows])
    # cut out and carried onto the light's plane only where used (not for pixels the
    # windings settle)
    flat = np.zeros((len(pix), width, 2))
    # a convex object seen from outside: one hull per (pixel, object)
    obj = objects.object[tri]
    hullable = objects.convex[tri] & _outside(objects, corners, p, pix, tri)
    if hullable.any():
        h = np.flatnonzero(hullable)
        flat[h] = carry(h)
        key = pix[h] * (objects.object.max() + 1) + obj[h]
        group, which = np.unique(key, return_inverse=True)
        mask = np.arange(flat.shape[1])[None] < count[h, None]
        points = shapely.multipoints(flat[h][mask], indices=np.repeat(which, count[h]))
        shapes.append(shapely.convex_hull(points))
        owner.append(group // (objects.object.max() + 1))
    rest = np.flatnonzero(~hullable)
    arranged = np.zeros(0, np.int64)
    many = np.bincount(pix[rest], minlength=len(p))
    crowd = many > MANY_PIECES
    heavy = rest[crowd[pix[rest]]]
    chains, loose = np.full(len(p), None, object), np.full(len(p), None, object)
    if len(rest) and outlines:
        # a pixel of more than WINDING_PIECES shadows, all of them here (no hull): measured
        # from its outline's windings
        alone = many > WINDING_PIECES
        alone[np.concatenate([bodies[2]] + owner).astype(np.int64)] = False
        chains, apart = windings.split(light, corners, p, pix, tri, rest, objects.corner_ids,
                                       alone)
        # the few shadows it leaves out, cut, carried and turned counter-clockwise: a pixel
        # with one whose corners do not certainly turn one way goes to the arrangement
        flat[apart] = carry(apart)
        turned, sure = windmeasures.turned(flat[apart], count[apart])
        chains[pix[apart[~sure]]] = None
        done = windings.found(chains)
        keep = np.flatnonzero(done[pix[apart]])
        for k, group in zip(*windings.groups(pix[apart[keep]], keep)):
            loose[k] = (turned[group], count[apart[group]])
        heavy, rest = heavy[~done[pix[heavy]]], rest[~done[pix[rest]]]
    used = np.union1d(heavy, rest)
    flat[used] = carry(used)
    if len(heavy):
        # many pieces: their union from its outline (`raytrace.arrange`)
        rest = rest[~crowd[pix[rest]]]
        united, arranged = arrange.unions(shapely, light, corners, p, flat, count, pix, tri,
                                          heavy, objects.corner_ids)
        shapes.append(united)
        owner.append(arranged)
    if len(rest):
        shapes.append(shapes_of(shapely, flat[rest], count[rest]))
        owner.append(pix[rest])
    return (*pixel_unions(shapely, bodies, shapes, owner, len(p), light.grid, outlines, arranged),
            chains, loose)


def _outside(objects: Objects, corners: np.ndarray, p: np.ndarray, pix: np.ndarray,
             tri: np.ndarray) -> np.ndarray:
    """(q,) bool: p[pix] lies outside the convex object of tri (q,) by more than
    CONVEX_RELATIVE: beyond one of its face planes (False for a non-convex object)."""
    out = np.zeros(len(pix), bool)
    for j in np.unique(objects.object[tri[objects.convex[tri]]]):
        faces = np.flatnonzero(objects.object == j)
        at = np.flatnonzero((objects.object[tri] == j) & objects.convex[tri])
        who, inv = np.unique(pix[at], return_inverse=True)
        n = objects.outward[faces]
        c = corners[faces][:, 0]
        off = p[who] @ n.T - (n * c).sum(axis=1)
        scale = np.maximum(np.abs(p[who]).max(axis=1), np.abs(corners[faces]).max())
        out[at] = (off.max(axis=1) > CONVEX_RELATIVE * scale)[inv]
    return out
