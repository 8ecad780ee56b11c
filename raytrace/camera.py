"""Primary rays, exactly as CONVENTIONS.md defines the camera and the pixels.

The basis is computed here from the `Camera` fields alone (not borrowed from the rasterizer: the
ray tracer is an independent witness).  OpenGL-style look-at: the camera looks down its -z axis,
x to the right, y up.
"""

from __future__ import annotations

import math

import numpy as np


def camera_basis(camera) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The camera's orthonormal basis in world space: right (x), up (y), back (z), each (3,)
    float64.  The view direction is -back."""
    back = camera.eye - camera.target
    back = back / np.linalg.norm(back)
    right = np.cross(camera.up, back)
    right = right / np.linalg.norm(right)
    up = np.cross(back, right)
    return right, up, back


def pixel_ndc(width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Normalised device coordinates of every pixel centre, row 0 at the TOP.

    Returns ndc_x, ndc_y : (height, width) float64, ((x + 0.5) / W * 2 - 1, 1 - (y + 0.5) / H * 2).
    """
    x = (np.arange(width) + 0.5) / width * 2.0 - 1.0
    y = 1.0 - (np.arange(height) + 0.5) / height * 2.0
    return np.broadcast_to(x[None, :], (height, width)), np.broadcast_to(y[:, None],
                                                                         (height, width))


def primary_rays(camera, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """One ray per pixel centre, starting where it crosses the near plane.

    Returns origins : (H*W, 3) float64 and directions : (H*W, 3) float64, unit length, in
    row-major pixel order (index = y * W + x, row 0 at the top), so `t` along a ray is a distance.

    In eye space the ray through NDC (sx, sy) has direction (sx * tan(fov_y / 2) * aspect,
    sy * tan(fov_y / 2), -1); scaled by `near` it reaches the near plane (eye-space depth == near,
    a plane, not a sphere), which is where the ray starts: geometry nearer than that is clipped,
    as in the rasterizer.
    """
    right, up, back = camera_basis(camera)
    sx, sy = pixel_ndc(width, height)
    half_h = math.tan(math.radians(camera.fov_y) / 2.0)
    half_w = half_h * (width / height)
    # Eye-space direction with depth 1, mapped to world space.
    d = ((sx * half_w).reshape(-1, 1) * right + (sy * half_h).reshape(-1, 1) * up - back)
    origins = camera.eye + camera.near * d
    directions = d / np.linalg.norm(d, axis=1, keepdims=True)
    return origins, directions
