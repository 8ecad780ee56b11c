"""The scene's triangles as the exact visibility queries them (`raytrace.exact_soft`): per
object whether it is closed and convex (then its shadow from a point outside is one convex
polygon), its silhouette from a point, and clusters of triangles with their boxes for the
conservative candidate query.  float64, numpy (the per-triangle and per-member arrays in
numba where it loads: `raytrace.occluderkernels`, the same bytes), in the masks' frame.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .polygons import dot, kernels, project

# An object is convex when no corner lies farther than this (of its largest coordinate) outside
# any of its face planes: its corners are float64 (the frame: world less the eye), each a few
# roundings (~1e-16 of its coordinate) off, so a flat face's two triangles can look ~1e-15
# concave; 2^-40 (~1e-12) is a thousand times that.  p is outside a convex object when
# farther than this beyond one of its face planes.
CONVEX_RELATIVE = 2.0 ** -40
# Objects with more faces than this are not tested for convexity (faces x corners work); they
# are united triangle by triangle, which is exact too.
CONVEX_TEST_FACES = 4096
# Triangles per cluster of the candidate query.
CLUSTER = 16
# Clusters per run (consecutive clusters, one box: a query passes over a run at once).
RUN = 16


class Objects(NamedTuple):
    """Per scene triangle: its object (M,) and whether that object is closed and convex
    (convex (M,) bool), with its outward face normals (M, 3) (0 for the others); and the
    candidate clusters: members (C, CLUSTER) int64 (−1 pads), lo, hi (C, 3) boxes, owner (C,)
    each cluster's object, centre (C, 3) and radius (C,) a sphere around each cluster's box;
    bodies: per object its `Convex`, or None; per triangle its box tri_lo, tri_hi (M, 3), unit
    normal (M, 3) (0 if degenerate), offset (M,) normal . corner and scale (M,) its largest
    corner coordinate; shell (M, 3): for a closed, consistently wound object (convex or not)
    its triangles' outward unit normals, 0 for the others; corner_ids (M, 3): each corner's
    index among the scene's distinct corners (welded by their coordinates); packed (C,
    CLUSTER, 16) float64: each member's tri_lo, tri_hi, normal, shell, first corner and
    scale side by side, in the members' order (the candidate query reads a cluster's
    members from one place, not from eight arrays at random: `raytrace.exactkernels.pairs`),
    kinds (C, CLUSTER) int64: each member's object * 4 + 1 where convex + 2 where it has a
    shell and is not convex; member_ids (C, CLUSTER, 3) int64: each member's corner_ids, in
    the members' order as packed (`raytrace.blockkernels.block_edges` reads them so);
    run_lo, run_hi (R, 3), run_centre (R, 3), run_radius (R,): the boxes of the runs of RUN
    consecutive clusters (the last one shorter; clusters follow a Morton curve within an
    object, so a run is compact), and a sphere about each that holds its clusters'
    spheres; holes: per object its holes' balls (`occluderkernels.holes`) and its box (its
    clusters'), for the block path's one-way rule (`raytrace.onewaykernels`), None without
    numba; cones (C, 5): each cluster's normal cone (`occluderkernels.cones`, the block
    path's test of a cluster turned away whole), None without numba."""

    object: np.ndarray
    convex: np.ndarray
    outward: np.ndarray
    members: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    owner: np.ndarray
    bodies: list
    centre: np.ndarray
    radius: np.ndarray
    tri_lo: np.ndarray
    tri_hi: np.ndarray
    normal: np.ndarray
    offset: np.ndarray
    scale: np.ndarray
    shell: np.ndarray
    corner_ids: np.ndarray | None = None
    packed: np.ndarray | None = None
    kinds: np.ndarray | None = None
    member_ids: np.ndarray | None = None
    run_lo: np.ndarray | None = None
    run_hi: np.ndarray | None = None
    run_centre: np.ndarray | None = None
    run_radius: np.ndarray | None = None
    holes: tuple | None = None
    cones: np.ndarray | None = None


class Convex(NamedTuple):
    """A closed, convex, consistently wound object: points (V, 3) its distinct corners,
    outward (F, 3) unit face normals, offset (F,) normal . corner, edges (E, 2) the corners
    and sides (E, 2) the two faces of each edge."""

    points: np.ndarray
    outward: np.ndarray
    offset: np.ndarray
    edges: np.ndarray
    sides: np.ndarray

    def silhouette(self, eye: np.ndarray) -> np.ndarray:
        """(n, V) bool: the corners on an edge between a face turned toward eye (n, 3) and
        one turned away (the hull of their shadows is the object's)."""
        toward = dot(eye[:, None], self.outward[None]) > self.offset
        cut = toward[:, self.sides[:, 0]] != toward[:, self.sides[:, 1]]
        out = np.zeros((len(eye), len(self.points)), bool)
        rows = np.nonzero(cut)
        out[rows[0], self.edges[rows[1], 0]] = True
        out[rows[0], self.edges[rows[1], 1]] = True
        return out

    def shadows(self, eye: np.ndarray, light) -> tuple[np.ndarray, np.ndarray]:
        """The object's shadows from eyes (n, 3) on the plane of `light` (a
        `lightshapes.FramedLight`), each eye beyond the object from the light (every corner
        strictly between the eye's parallel plane and the light's): (corners (n, k, 2) in the
        plane's coordinates, count (n,), 0 where fewer than 3), the convex polygon of the
        silhouette's corners' shadows in order of angle about their mean, counter-clockwise
        (they all lie on its outline), each row's last corner repeated to k.  In numba where
        it loads (`occluderkernels.hull_shadows`: the same floats and order)."""
        loaded = kernels("occluderkernels")
        args = (light.center, light.normal, light.axes)
        if loaded is not None:
            return loaded.hull_shadows(self.points, self.outward, self.offset, self.edges,
                                       self.sides, np.ascontiguousarray(eye, np.float64),
                                       *(np.ascontiguousarray(a, np.float64) for a in args))
        n = len(eye)
        row, corner = np.nonzero(self.silhouette(eye))
        flat = project(self.points[corner][:, None], eye[row], *args)[:, 0]
        many = np.bincount(row, minlength=n)
        mean = np.stack([np.bincount(row, flat[:, k], n) for k in (0, 1)], 1)
        rel = flat - mean[row] / np.maximum(many[row, None], 1)
        flat = flat[np.lexsort((np.arctan2(rel[:, 1], rel[:, 0]), row))]
        first = np.r_[0, np.cumsum(many)[:-1]]
        at = first[:, None] + np.minimum(np.arange(max(int(many.max(initial=0)), 1))[None],
                                         np.maximum(many - 1, 0)[:, None])
        out = flat[np.minimum(at, len(flat) - 1)] if len(flat) else np.zeros((n, 1, 2))
        out[many == 0] = 0.0
        return out, np.where(many >= 3, many, 0)


def objects(corners: np.ndarray, ids: np.ndarray, casts: np.ndarray | None = None,
            welded: np.ndarray | None = None) -> Objects:
    """The `Objects` of triangles corners (M, 3, 3) of objects ids (M,); `casts` (n_objects,)
    bool: the objects that cast shadows (`cast_shadows`; default all): only theirs are in the
    clusters and bodies (the others are met by no query); welded (M, 3): each corner's index
    among the distinct corners (by their coordinates; default: welded here)."""
    M = len(corners)
    welded = (weld(corners.reshape(-1, 3)) if welded is None else welded).reshape(-1, 3)
    convex = np.zeros(M, bool)
    outward = np.zeros((M, 3))
    loaded = kernels("occluderkernels")
    if loaded is not None:
        normals, length = loaded.normals(corners)
        length = length[:, None]
    else:
        normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        length = np.linalg.norm(normals, axis=1, keepdims=True)
        normals = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)
    members, owner, bodies = [], [], []
    n_objects = int(ids.max(initial=-1)) + 1
    shell = np.zeros((M, 3))
    for j in range(n_objects):
        where = tris = np.flatnonzero(ids == j)
        bodies.append(None)
        if len(tris) == 0 or (casts is not None and not casts[j]):
            continue
        if tris[-1] - tris[0] + 1 == len(tris):     # side by side: views, not copies
            tris = slice(int(tris[0]), int(tris[-1]) + 1)
        c = corners[tris]
        topology = _topology(c, welded[tris])
        if topology is not None and (length[tris] > 0).all():
            sign = 1.0 if np.einsum("ij,ij->i", c[:, 0], np.cross(c[:, 1], c[:, 2])).sum() > 0 \
                else -1.0
            n = normals[tris] * sign
            shell[tris] = n
        if topology is not None and (length[tris] > 0).all() and \
                len(where) <= CONVEX_TEST_FACES:
            points = topology[0]
            offset = (n * c[:, 0]).sum(axis=1)
            off = n @ points.T - offset[:, None]
            if off.max() <= CONVEX_RELATIVE * np.abs(points).max():
                convex[tris] = True
                outward[tris] = n
                bodies[-1] = Convex(points, n, offset, *topology[1:])
        # clusters of consecutive triangles along a Morton (Z-order) curve of their centres:
        # compact clusters, whose boxes the pyramid's box misses more often
        # (their means, summed as numpy's mean sums three: the same floats)
        order = where[_stable_order(_morton((c[:, 0] + c[:, 1] + c[:, 2]) / 3))]
        pad = -len(order) % CLUSTER
        members.append(np.concatenate([order, np.full(pad, -1)]).reshape(-1, CLUSTER))
        owner.append(np.full(len(members[-1]), j))
    members = np.concatenate(members) if members else np.zeros((0, CLUSTER), np.int64)
    owner = np.concatenate(owner) if owner else np.zeros(0, np.int64)
    kind = ids.astype(np.int64) * 4 + convex + 2 * ((shell != 0).any(axis=1) & ~convex)
    tri_lo, tri_hi, scale, offset, packed, lo, hi, kinds, member_ids = \
        loaded.fields(corners, normals, shell, kind, welded, members) \
        if loaded is not None and M else _fields(corners, normals, shell, kind, welded, members)
    centre = (lo + hi) / 2
    # the half diagonal, a little more for its own rounding: the sphere must hold the box
    radius = np.linalg.norm(hi - lo, axis=1) / 2 * (1 + 1e-12) + 1e-300
    runs = np.arange(0, len(members), RUN)
    run_lo = np.minimum.reduceat(lo, runs, axis=0) if len(runs) else np.zeros((0, 3))
    run_hi = np.maximum.reduceat(hi, runs, axis=0) if len(runs) else np.zeros((0, 3))
    run_centre = (run_lo + run_hi) / 2
    # the farthest of its clusters' spheres from its centre, a little more for the rounding
    reach = np.linalg.norm(centre - np.repeat(run_centre, RUN, axis=0)[:len(centre)],
                           axis=1) + radius
    run_radius = np.maximum.reduceat(reach, runs) * (1 + 2.0 ** -30) if len(runs) else \
        np.zeros(0)
    holes = None if loaded is None or not M else loaded.holes(
        welded, corners, np.where(casts[ids], ids, -1).astype(np.int64) if casts is not None
        else ids.astype(np.int64), n_objects) + _boxes(owner, lo, hi, n_objects)
    return Objects(ids.astype(np.int64), convex, outward, members, lo, hi, owner, bodies,
                   centre, radius, tri_lo, tri_hi, normals, offset, scale, shell, welded, packed,
                   kinds, member_ids, run_lo, run_hi, run_centre, run_radius, holes,
                   None if loaded is None or not M else loaded.cones(packed, members))


def _boxes(owner: np.ndarray, lo: np.ndarray, hi: np.ndarray, n: int
           ) -> tuple[np.ndarray, np.ndarray]:
    """Each of n objects' box (lo, hi (n, 3); +-inf where it has no cluster): its clusters'
    boxes (lo, hi (C, 3)) reduced, its clusters (owner (C,)) side by side."""
    box_lo, box_hi = np.full((n, 3), np.inf), np.full((n, 3), -np.inf)
    if len(owner):
        first = np.flatnonzero(np.r_[True, owner[1:] != owner[:-1]])
        box_lo[owner[first]] = np.minimum.reduceat(lo, first, axis=0)
        box_hi[owner[first]] = np.maximum.reduceat(hi, first, axis=0)
    return box_lo, box_hi


def _fields(corners: np.ndarray, normals: np.ndarray, shell: np.ndarray, kind: np.ndarray,
            welded: np.ndarray, members: np.ndarray) -> tuple[np.ndarray, ...]:
    """`occluderkernels.fields` in numpy (installs without numba; the same bytes)."""
    M = len(corners)
    # the corners' minima and maxima (elementwise over the three: a reduction along a short
    # axis is numpy's slow one; the same values)
    tri_lo = np.minimum(np.minimum(corners[:, 0], corners[:, 1]), corners[:, 2])
    tri_hi = np.maximum(np.maximum(corners[:, 0], corners[:, 1]), corners[:, 2])
    far = np.maximum(np.abs(tri_lo), np.abs(tri_hi))
    scale = np.maximum(np.maximum(far[:, 0], far[:, 1]), far[:, 2])
    at = np.maximum(members, 0)
    packed = np.concatenate([tri_lo, tri_hi, normals, shell, corners[:, 0], scale[:, None]],
                            axis=1)[at] if M else np.zeros(members.shape + (16,))
    # a cluster's box: its members' boxes' (the same minima and maxima as their corners'),
    # member by member (numpy's reduction along the middle axis is the slow one)
    lo, hi = np.full((len(members), 3), np.inf), np.full((len(members), 3), -np.inf)
    for k in range(members.shape[1]):
        use = (members[:, k] >= 0)[:, None]
        lo = np.minimum(lo, np.where(use, packed[:, k, :3], np.inf))
        hi = np.maximum(hi, np.where(use, packed[:, k, 3:6], -np.inf))
    return (tri_lo, tri_hi, scale, (normals * corners[:, 0]).sum(axis=1), packed, lo, hi,
            kind[at] if M else np.zeros(members.shape, np.int64),
            welded[at] if M else np.zeros(members.shape + (3,), np.int64))


def weld(points: np.ndarray) -> np.ndarray:
    """(n,) int64: each of points (n, 3) (finite) numbered among the distinct ones, in their
    order by x, then y, then z (np.unique(points, axis=0, return_inverse=True)'s numbers:
    equal as floats, -0.0 with 0.0).  One sort by x, then the runs of equal x by y and z (equal
    points take one number in any order, so no sort need be stable): the bunny's 35k
    corners ~4x faster than three stable sorts of the columns, twice as fast as np.unique."""
    order = np.argsort(points[:, 0])
    xs = points[order, 0]
    same = xs[1:] == xs[:-1]                  # each point's x as its predecessor's
    tied = np.r_[same, False] | np.r_[False, same]
    if tied.any():
        at = np.flatnonzero(tied)
        run = np.cumsum(np.r_[True, ~same])[at]
        sub = order[at]
        order[at] = sub[np.lexsort((points[sub, 2], points[sub, 1], run))]
    ranked = points[order]
    new = np.r_[True, (ranked[1:] != ranked[:-1]).any(axis=1)] if len(points) else \
        np.zeros(0, bool)
    number = np.empty(len(points), np.int64)
    number[order] = np.cumsum(new) - 1
    return number


def _stable_order(codes: np.ndarray) -> np.ndarray:
    """np.argsort(codes, kind="stable") of (n,) int64 codes in [0, 2^32): one sort of each
    code with its place in the low bits (numpy's sort of int64 keys, not its slower stable
    argsort), where those fit in an int64."""
    n = len(codes)
    bits = max(1, int(n - 1).bit_length())
    if n == 0 or bits > 30 or codes.min() < 0 or codes.max() >= 1 << 32:
        return np.argsort(codes, kind="stable")
    return np.sort((codes << bits) | np.arange(n)) & ((1 << bits) - 1)


def _spread_bits() -> np.ndarray:
    """(1024,) int64: each ten-bit number's bits spread two apart (bit b at bit 3 b), by
    shifts and masks."""
    x = np.arange(1024, dtype=np.int64)
    for shift, mask in ((16, 0x030000FF), (8, 0x0300F00F), (4, 0x030C30C3), (2, 0x09249249)):
        x = (x | (x << shift)) & mask
    return x


_SPREAD = _spread_bits()


def _morton(points: np.ndarray) -> np.ndarray:
    """(n,) int64 Morton codes of points (n, 3) on a 1024^3 grid over their box: bit b of
    axis a at bit 3 b + a (each axis's ten bits spread two apart, looked up in a table: a
    third of the shifts' time)."""
    # column by column: numpy reduces an (n, 3) array along its first axis 20x slower
    lo = np.array([points[:, a].min() for a in range(3)])
    span = np.array([points[:, a].max() for a in range(3)]) - lo
    cell = np.floor((points - lo) / np.where(span > 0, span, 1) * 1023.999).astype(np.int64)
    return _SPREAD[cell[:, 0]] | (_SPREAD[cell[:, 1]] << 1) | (_SPREAD[cell[:, 2]] << 2)


def _topology(corners: np.ndarray, welded: np.ndarray):
    """For triangles (F, 3, 3) with welded corners (F, 3) (`objects`) that make a closed,
    consistently wound surface (every edge met exactly once each way): (points (V, 3), edges
    (E, 2) corner indices, sides (E, 2) the two faces of each); None for any other."""
    if not _closed(welded):
        return None
    _, first, vid = np.unique(welded.reshape(-1), return_index=True, return_inverse=True)
    points = corners.reshape(-1, 3)[first]
    vid = vid.reshape(-1, 3)
    V = len(points)
    a = np.concatenate([vid[:, 0], vid[:, 1], vid[:, 2]])
    b = np.concatenate([vid[:, 1], vid[:, 2], vid[:, 0]])
    face = np.tile(np.arange(len(vid)), 3)
    if (a == b).any():
        return None
    key = a * V + b
    order = np.argsort(key)
    if (np.diff(key[order]) == 0).any():
        return None
    at = np.searchsorted(key[order], b * V + a)
    if (at >= len(key)).any() or (key[order][np.minimum(at, len(key) - 1)] != b * V + a).any():
        return None
    twin = face[order][at]
    once = a < b
    return (points, np.stack([a[once], b[once]], axis=1),
            np.stack([face[once], twin[once]], axis=1))


def _closed(welded: np.ndarray) -> bool:
    """Whether triangles of welded corners (F, 3) could make a closed, consistently wound
    surface (`_topology`'s test, on the welded ids themselves: no edge from a corner to
    itself, each directed edge once and its reverse there too); two sorts, no renumbering,
    so an open mesh (most scanned ones) costs less than half of `_topology`."""
    loaded = kernels("occluderkernels")
    # the two refusals below (numpy's) in one pass (6 -> 1 ms), before the edges are gathered
    if loaded is not None and not loaded.paired(np.ascontiguousarray(welded, np.int64)):
        return False
    V = int(welded.max(initial=-1)) + 1
    a = welded.reshape(-1)
    b = welded[:, [1, 2, 0]].reshape(-1)
    if loaded is None:
        if (a == b).any():
            return False
        # a closed one's edges are their reverses, so sum f(a) g(b) over them is sum f(b)
        # g(a) (any f, g; uint64 products and sums wrap alike): where they differ it is
        # open, without the sorts (the bunny's 70k triangles, open: 22 -> 6 ms)
        fa, fb, ga, gb = _spread(a, 1), _spread(b, 1), _spread(a, 2), _spread(b, 2)
        if np.sum(fa * gb) != np.sum(fb * ga):
            return False
    key = np.sort(a * V + b)
    if (np.diff(key) == 0).any():
        return False
    # each directed edge once: every reverse is there where the reverses, sorted, are the
    # edges (a sort of sorted-like keys, not a search of each)
    return bool(len(key)) and np.array_equal(np.sort(b * V + a), key)


def _spread(ids: np.ndarray, seed: int) -> np.ndarray:
    """(n,) uint64: ids (n,) int64 >= 0 mixed (a multiply and shift, as `_closed`'s f and g,
    a different one per seed; products wrap)."""
    x = (ids.astype(np.uint64) + np.uint64(seed)) * np.uint64(0x9E3779B97F4A7C15)
    return x ^ (x >> np.uint64(29))
