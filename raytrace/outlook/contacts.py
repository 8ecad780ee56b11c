"""Contact lines: where an edge of one surface lies on another's plane (a block standing on a
floor), the lower surface is cut along that edge's line before radiosity meshes it.

Why: a patch is one constant.  A floor patch that runs under a block averages its lit part with
the buried part beneath, so it shows too dark, shoots too little light at the block's foot, and
its buried rays pour light into the block's inside; the blocks came out 1-2 % dark at every
level and seed.  Cut at the contact, every patch is wholly outside or wholly beneath (Heckbert's
D0 discontinuity meshing, the contact case only).

Found in the scene's float64 triangles: an edge of triangle B is a contact of triangle A when
both its ends lie on A's plane within `CONTACT_RELATIVE` of the largest coordinate, B is not
parallel to A (a coplanar decal or A's neighbour is no contact), the edge overlaps A's interior
and its line splits A.  Pairs are tested by brute force over bounding boxes, in chunks; the
pieces are convex polygons, fanned into triangles with A's winding.
"""

from __future__ import annotations

import numpy as np

CONTACT_RELATIVE = 1e-7  # on a plane: within this fraction of the largest |coordinate|
PARALLEL_COS = 1.0 - 1e-9  # |n_A · n_B| above this: the two planes are the same direction
PAIR_CHUNK = 1 << 22  # triangle-edge pairs tested per step (bounds memory)
SIDE_CODE_BASE = 1 << 20  # `sides`: a corner on up to three segments gets a distinct code


def unit_normals(corners: np.ndarray) -> np.ndarray:
    """(T, 3) unit winding normals of triangles (T, 3, 3)."""
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    return cross / np.maximum(np.linalg.norm(cross, axis=1), 1e-300)[:, None]


def contact_cuts(corners: np.ndarray) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """Triangles (T, 3, 3) float64 -> [(triangle, point (3,), direction (3,))], the lines to cut
    each triangle along (see the module docstring)."""
    T = len(corners)
    n = unit_normals(corners)
    d = (n * corners[:, 0]).sum(axis=1)
    p = corners.reshape(-1, 3)
    q = np.roll(corners, -1, axis=1).reshape(-1, 3)
    owner = np.repeat(np.arange(T), 3)
    eps = _eps(corners)
    lo, hi = corners.min(axis=1) - eps, corners.max(axis=1) + eps
    elo, ehi = np.minimum(p, q), np.maximum(p, q)
    cuts = []
    step = max(1, PAIR_CHUNK // max(len(p), 1))
    for first in range(0, T, step):
        a = np.arange(first, min(first + step, T))
        on = ((np.abs(p @ n[a].T - d[a]) <= eps) & (np.abs(q @ n[a].T - d[a]) <= eps)).T
        on &= np.abs(n[a] @ n[owner].T) < PARALLEL_COS
        on &= (lo[a, None] <= ehi[None]).all(axis=2) & (elo[None] <= hi[a, None]).all(axis=2)
        for i, e in zip(*np.nonzero(on)):
            if _overlaps(corners[a[i]], n[a[i]], p[e], q[e], eps):
                cuts.append((int(a[i]), p[e], q[e] - p[e]))
    return cuts


def split_at_contacts(corners: np.ndarray, ids: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Triangles (T, 3, 3) and their objects (T,) -> the same surfaces with every contact line
    cut: (T', 3, 3), (T',), the cut triangles' pieces last, same winding, same total area; and
    the contacts (C, 3, 3): each edge's two ends and the unit normal of the plane it cut."""
    cuts = contact_cuts(corners)
    n = unit_normals(corners)
    segments = np.array([(p, p + d, n[t]) for t, p, d in cuts]).reshape(-1, 3, 3)
    if not cuts:
        return corners, ids, segments
    eps = _eps(corners)
    lines: dict[int, list] = {}
    for tri, point, direction in cuts:
        lines.setdefault(tri, []).append((point, direction))
    keep = np.ones(len(corners), bool)
    pieces, piece_ids = [], []
    for tri, cuts_of_tri in lines.items():
        polygons = [corners[tri]]
        for point, direction in cuts_of_tri:
            side = np.cross(direction, n[tri])
            side /= np.linalg.norm(side)
            polygons = [part for poly in polygons for part in _clip(poly, point, side, eps)]
        for poly in polygons:
            pieces += [np.stack([poly[0], poly[k], poly[k + 1]]) for k in range(1, len(poly) - 1)]
            piece_ids += [ids[tri]] * (len(poly) - 2)
        keep[tri] = False
    return (np.concatenate([corners[keep], np.array(pieces)]),
            np.concatenate([ids[keep], np.array(piece_ids, dtype=ids.dtype)]), segments)


def sides(points: np.ndarray, centres: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """(k,) int64: for patch corners `points` (k, 3) of patches with `centres` (k, 3), a code
    of the side of each contact segment (C, 3, 3) that the patch lies on, over the segments
    the corner lies on (0 when none): corners on a contact are shared only by patches on the
    same side of it."""
    code = np.zeros(len(points), np.int64)
    eps = _eps(points) if len(points) else 0.0
    for c, (p, q, n) in enumerate(segments):
        along = q - p
        length = float(np.linalg.norm(along))
        unit = along / length
        side = np.cross(unit, n)
        rel = points - p
        t = rel @ unit
        off = rel - t[:, None] * unit
        on = (np.linalg.norm(off, axis=1) <= eps) & (t >= -eps) & (t <= length + eps)
        s = (centres - p) @ side
        sign = np.where(s > eps, 1, np.where(s < -eps, -1, 0))
        code += np.where(on, sign * (c + 1), 0) * SIDE_CODE_BASE ** (c % 3)
    return code


def _eps(corners: np.ndarray) -> float:
    return CONTACT_RELATIVE * max(float(np.abs(corners).max()), 1e-300)


def _overlaps(c: np.ndarray, n: np.ndarray, p: np.ndarray, q: np.ndarray, eps: float) -> bool:
    """Whether segment pq, on triangle c's plane (normal n), runs through c's interior for more
    than eps and its line has corners of c on both sides."""
    side = np.cross(q - p, n)
    side /= np.linalg.norm(side)
    s = (c - p) @ side
    if not (s.max() > eps and s.min() < -eps):
        return False
    t0, t1 = 0.0, 1.0  # Liang-Barsky: the part of pq inside the three edges' half-planes
    for k in range(3):
        a, b = c[k], c[(k + 1) % 3]
        inward = np.cross(n, b - a)
        inward /= np.linalg.norm(inward)
        f0, df = (p - a) @ inward, (q - p) @ inward
        if df == 0.0:
            if f0 < eps:
                return False
        elif df > 0.0:
            t0 = max(t0, -f0 / df)
        else:
            t1 = min(t1, -f0 / df)
    return (t1 - t0) * float(np.linalg.norm(q - p)) > eps


def _clip(poly: np.ndarray, point: np.ndarray, side: np.ndarray, eps: float) -> list:
    """A convex polygon (k, 3) cut by the line through `point` across unit `side`: one or two
    convex polygons, corners in the same order."""
    s = (poly - point) @ side
    if s.max() <= eps or s.min() >= -eps:
        return [poly]
    halves: tuple[list, list] = ([], [])
    k = len(poly)
    for i in range(k):
        a, b, sa, sb = poly[i], poly[(i + 1) % k], s[i], s[(i + 1) % k]
        if sa >= -eps:
            halves[0].append(a)
        if sa <= eps:
            halves[1].append(a)
        if (sa > eps and sb < -eps) or (sa < -eps and sb > eps):
            x = a + (b - a) * (sa / (sa - sb))
            halves[0].append(x)
            halves[1].append(x)
    return [np.array(h) for h in halves if len(h) >= 3]
