"""Huge triangles clipped on the CPU, in float64, to a guard band of the view.

Why: llvmpipe loses coverage at the image border for a triangle reaching ~1e6 times the near
distance from the eye (a ground quad 1e5-1e7 wide seen from a few units up: up to hundreds of
pixels of a 96x72 image uncovered, `tests/raster/test_large_worlds.py`), and so do such a
triangle's shadow volume faces (its silhouette's side quads, its far cap: z-fail counts lost in
the same band).  By diagnosis GL clips such a triangle itself, in float32 clip coordinates of
the size of its far corners, too coarse for them: the clipped polygon's edges land inside the
view.  (Not the world-space upload: the loss stays in the eye's frame; cut here first, in
float64, to within GUARD of the view's edges and beyond half the near distance, every loss
seen is gone.)  The same cut is applied to the volumes in homogeneous coordinates
(`volumes.cpu.CpuVolumes._guard_sides`, `volumes.builder.far_cap_pieces`).

Why it changes nothing that is seen: every pixel's view ray runs from the eye inside the view
pyramid, which lies inside the guard pyramid; the part of a triangle outside the guard pyramid
meets no view ray, and the part inside is kept.  The new edges lie on the guard planes, outside
the view, so no visible edge moves.  The pieces are cut in float64 from the triangle's float32
corners (the ones both renderers trace, `projection.to_frame`), so they lie on that float32
triangle's plane; rounded to float32, a new corner moves off it by at most half a float32
spacing of its own coordinates (none at all along an axis the triangle is flat in: a
horizontal ground keeps its exact float32 height), which is the order of the rounding of the
triangle's own corners, the limit documented in docs/robustness.md.

Only triangles that reach beyond HUGE_REACH near distances from the eye and leave the guard
pyramid are cut, so the triangles of every ordinary scene go to GL as they are.  Shading,
ground truth and the shadow volumes' near caps see each piece as its triangle: it carries the
triangle's key, normal, first corner and object (`SceneGeometry.set_view`).
"""

from __future__ import annotations

import numpy as np

# The guard band: the pieces lie within |x|, |y| <= GUARD * w in clip space (GUARD times the
# view's half-width from its centre) and at least NEAR_GUARD * near in front of the eye.
GUARD = 4.0
NEAR_GUARD = 0.5
# A triangle is cut only if some corner lies farther than this many near distances from the
# eye (and it leaves the guard pyramid).  Coverage was lost from ~1e6 (issue 10); ordinary
# scenes (40 units wide, near 0.01) stay below 1e4.
HUGE_REACH = 2.0 ** 16


def guard_planes(view_proj: np.ndarray, near: float) -> np.ndarray:
    """(5, 4) float64 planes (a, d) of frame points x, a . x + d >= 0 inside the guard
    pyramid: GUARD * w -+ x, GUARD * w -+ y >= 0 and w >= NEAR_GUARD * near, from the (4, 4)
    frame -> clip matrix (clip w = eye-space depth)."""
    x, y, w = view_proj[0], view_proj[1], view_proj[3]
    planes = np.array([GUARD * w - x, GUARD * w + x, GUARD * w - y, GUARD * w + y, w])
    planes[4, 3] -= NEAR_GUARD * near
    return planes


def reach(corners: np.ndarray) -> np.ndarray:
    """(M,) float64: the largest distance from the eye (the frame's origin) of each triangle's
    corners, (M, 3, 3) points or (M, 3, 4) homogeneous with w 1 or 0 (a point at infinity, a
    direction, counts 0: its size says nothing about its precision)."""
    c = np.asarray(corners, np.float64)
    length = np.sqrt((c[..., :3] ** 2).sum(axis=-1))
    if c.shape[-1] == 4:
        length = np.where(c[..., 3] != 0.0, length, 0.0)
    return length.max(axis=1)


def huge(corners: np.ndarray, reaches: np.ndarray, planes: np.ndarray, near: float
         ) -> np.ndarray:
    """(k,) int64: the triangles to cut.  corners (M, 3, 3) float64 points or (M, 3, 4)
    homogeneous, in the frame; reaches (M,) their `reach`; planes : `guard_planes`."""
    far = np.flatnonzero(reaches > HUGE_REACH * near)
    if len(far) == 0:
        return far
    c = _homogeneous(corners[far])
    inside = (np.einsum("mkj,pj->mkp", c, planes) >= 0.0).all(axis=(1, 2))
    return far[~inside]


def _homogeneous(points: np.ndarray) -> np.ndarray:
    points = np.asarray(points, np.float64)
    if points.shape[-1] == 4:
        return points
    return np.concatenate([points, np.ones(points.shape[:-1] + (1,))], axis=-1)


def clip_polygon(polygon: np.ndarray, planes: np.ndarray) -> np.ndarray:
    """(n, 3) points or (n, 4) homogeneous (w >= 0) float64 convex polygon -> (k, 3 or 4)
    float64, its part where every plane (p, 4) a . x + d w >= 0 (Sutherland-Hodgman, in
    float64; linear in homogeneous coordinates, so a side quad reaching infinity is clipped as
    it is drawn), in the same order; k = 0 if none."""
    width = polygon.shape[1]
    polygon = _homogeneous(polygon)
    for a in planes:
        if len(polygon) == 0:
            break
        dist = polygon @ a
        keep = []
        for i in range(len(polygon)):
            j = (i + 1) % len(polygon)
            if dist[i] >= 0.0:
                keep.append(polygon[i])
            if (dist[i] >= 0.0) != (dist[j] >= 0.0):
                t = dist[i] / (dist[i] - dist[j])
                keep.append(polygon[i] + t * (polygon[j] - polygon[i]))
        polygon = np.array(keep).reshape(-1, 4)
    return polygon[:, :width]


def cut(corners: np.ndarray, planes: np.ndarray) -> np.ndarray:
    """(3, k) float64 triangle (k = 3 points, 4 homogeneous) -> (p, 3, k) float64 triangles
    tiling its part inside the guard pyramid, wound as it is (a fan from the clipped polygon's
    first corner)."""
    poly = clip_polygon(corners, planes)
    if len(poly) < 3:
        return np.zeros((0, 3, corners.shape[1]))
    fan = np.arange(1, len(poly) - 1)
    return np.stack([np.repeat(poly[:1], len(fan), axis=0), poly[fan], poly[fan + 1]], axis=1)
