"""Exact depth: each covered pixel's centre ray met with its visible triangle's plane.

The depth buffer holds near / d in float32, interpolated in screen space across the triangle:
on a triangle whose corners lie far from the pixel's point (a huge ground seen near its horizon)
that rounding reaches ~1e-4 relative.  The G-buffer names each pixel's triangle, so the depth is
computed as the ray tracer computes it (`raytrace.masks._primary_hits`, the same float64
operations in the same order): the pixel-centre direction v of eye-space depth 1 from the eye
e meets the plane n . p = n . a of the triangle's float32 frame corners (a, b, c), n the unit
(b - a) x (c - a), at depth s = (n . a - n . e) / (n . v), rounded once.
"""

from __future__ import annotations

import numpy as np

from shadowvol.cameras import look_at_basis, pinhole
from shadowvol.raster.projection import frame_camera
from shadowvol.raster.truth import plane_kernel
from shadowvol.scene import Camera


def direction_grid(camera: Camera, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """col (3, W) and row (3, H) float64: pixel (x, y)'s direction of eye-space depth 1 is
    row[:, y] + col[:, x], summed as `raytrace.camera.RayGrid` sums it."""
    right, up, back = look_at_basis(camera)
    fx, fy, cx, cy = pinhole(camera, width, height)
    x = (np.arange(width) + 0.5 - cx) / fx
    y = (cy - (np.arange(height) + 0.5)) / fy
    return right[:, None] * x - back[:, None], up[:, None] * y


def plane_depths(geometry, camera: Camera, triangle: np.ndarray, fallback: np.ndarray
                 ) -> np.ndarray:
    """(H, W) float32 eye-space depth of each pixel's triangle plane.

    triangle : (H, W) int64 soup triangle per pixel (`read_surface` through
    `SceneGeometry.triangle_of_key`), -1 where nothing is drawn; fallback : (H, W) float32
    depth from the depth buffer, kept where nothing is drawn and where the plane gives no
    positive finite depth (a triangle seen exactly edge-on, a degenerate one)."""
    out = fallback.copy()
    height, width = fallback.shape
    pixel = np.flatnonzero(triangle >= 0)
    if len(pixel) == 0:
        return out
    keys = triangle.reshape(-1)[pixel]
    if geometry.triangle_count <= len(keys):   # every triangle's plane: cheaper than a sort
        corners, which = geometry.frame_corners(), keys
    else:
        tris, which = np.unique(keys, return_inverse=True)
        corners = geometry.frame_corners(tris)
    corners = corners.astype(np.float64)                                    # (k, 3, 3)
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.divide(n, length, out=np.zeros_like(n), where=length > 0)
    plane_d = np.einsum("...i,...i->...", n, corners[:, 0])
    local = frame_camera(camera, geometry.origin)
    col, row = direction_grid(local, width, height)
    with np.errstate(divide="ignore", invalid="ignore"):
        num = plane_d - n @ local.eye
    if plane_kernel.depths is not None:   # the same operations per pixel, compiled
        plane_kernel.depths(pixel, np.ascontiguousarray(which, np.int64), width,
                            np.ascontiguousarray(row), np.ascontiguousarray(col),
                            np.ascontiguousarray(n), num, out.reshape(-1))
        return out
    rows, cols = np.divmod(pixel, width)
    # n . v = n0 v0 + n1 v1 + n2 v2, left to right, v = row + col per component
    n_dot_v = np.zeros(len(pixel))
    for k in range(3):
        term = row[k][rows]
        term += col[k][cols]
        term *= n[:, k][which]
        n_dot_v += term
    with np.errstate(divide="ignore", invalid="ignore"):
        s = num[which] / n_dot_v
    good = np.isfinite(s) & (s > 0)
    out.reshape(-1)[pixel[good]] = s[good]
    return out
