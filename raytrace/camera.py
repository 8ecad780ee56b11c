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
    """Normalised device coordinates of the pixel centres (CONVENTIONS.md), row 0 at the TOP.

    Returns ndc_x : (W,) float64, (x + 0.5) / W * 2 - 1 per column, and ndc_y : (H,) float64,
    1 - (y + 0.5) / H * 2 per row.
    """
    return ((np.arange(width) + 0.5) / width * 2.0 - 1.0,
            1.0 - (np.arange(height) + 0.5) / height * 2.0)


class RayGrid:
    """The primary rays of a W x H image, factored: the direction through pixel (x, y), scaled to
    eye-space depth 1, is  col[:, x] + row[:, y]  with

        col[:, x] = ndc_x · tan(fov_y / 2) · aspect · right − back     (3, W)
        row[:, y] = ndc_y · tan(fov_y / 2) · up                        (3, H)

    and the ray starts on the near plane at  eye + near · direction.  Stored component-major
    (3, n) in `dtype` because numpy is fast on long contiguous rows (the masks' hot path).
    """

    def __init__(self, camera, width: int, height: int, dtype=np.float64):
        right, up, back = camera_basis(camera)
        x, y = pixel_ndc(width, height)
        half_h = math.tan(math.radians(camera.fov_y) / 2.0)
        half_w = half_h * (width / height)
        self.width, self.height, self.dtype = width, height, dtype
        self.eye = camera.eye.astype(dtype)
        self.near = dtype(camera.near)
        self.col = (right[:, None] * (x * half_w) - back[:, None]).astype(dtype)
        self.row = (up[:, None] * (y * half_h)).astype(dtype)

    def directions(self, rows: slice | None = None) -> np.ndarray:
        """(3, R*W) directions of eye-space depth 1 for the image rows `rows` (default all),
        row-major pixel order within them."""
        r = self.row[:, rows or slice(None)]
        return (r[:, :, None] + self.col[:, None, :]).reshape(3, -1)

    def origins(self, directions: np.ndarray) -> np.ndarray:
        """(3, n) ray starts on the near plane for directions (3, n) of depth 1."""
        return self.eye[:, None] + self.near * directions


def primary_rays(camera, width: int, height: int, rows: slice | None = None,
                 dtype=np.float64, unit: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """One ray per pixel centre, starting where it crosses the near plane.

    rows  : the image rows to make rays for (default: all), row 0 at the top.
    dtype : float64, or float32.
    unit  : normalise the directions (then t along a ray is a distance); if False, each
            direction has eye-space depth 1 (its component along the view axis is 1).
    Returns origins : (R*W, 3) and directions : (R*W, 3) of `dtype`, in row-major pixel order
    (index = row * W + x within `rows`).

    In eye space the ray through NDC (sx, sy) has direction (sx * tan(fov_y / 2) * aspect,
    sy * tan(fov_y / 2), -1); scaled by `near` it reaches the near plane (eye-space depth == near,
    a plane, not a sphere), which is where the ray starts: geometry nearer than that is clipped,
    as in the rasterizer.
    """
    grid = RayGrid(camera, width, height, dtype)
    d = grid.directions(rows)
    origins = grid.origins(d).T.copy()
    if unit:
        d = d / np.sqrt((d * d).sum(axis=0))
    return origins, d.T.copy()


def sample_rays(camera, width: int, height: int, pixels: np.ndarray, offsets: np.ndarray,
                lens: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Rays through points inside the pixels, through a thin lens: distributed ray tracing's
    primary rays (the masks keep `primary_rays`, the pixel centres).

    pixels  : (P,) int, row-major pixel indices y * W + x, row 0 at the top.
    offsets : (P, S, 2) float64, each ray's position in pixel units from its pixel's top-left
              corner (x right, y down); 0.5 is the centre, as in `pixel_ndc`.
    lens    : (P, S, 2) float64 points of the unit disk, scaled by `camera.aperture` (the
              lens radius) along right and up; None or aperture 0: a pinhole.
    Returns origins, unit directions : (P*S, 3) float64, sample-minor (the i-th pixel's
    samples at i*S .. i*S + S - 1).  A lens ray aims where the pinhole ray of the same pixel
    position meets the plane of focus (eye-space depth `camera.focus`): that plane is sharp.
    Every ray starts on the near plane.
    """
    right, up, back = camera_basis(camera)
    half_h = math.tan(math.radians(camera.fov_y) / 2.0)
    half_w = half_h * (width / height)
    px = (pixels % width)[:, None] + offsets[..., 0]
    py = (pixels // width)[:, None] + offsets[..., 1]
    x = (px / width * 2.0 - 1.0).reshape(-1)
    y = (1.0 - py / height * 2.0).reshape(-1)
    d = up * (y * half_h)[:, None] + (right * (x * half_w)[:, None] - back)  # depth 1
    start = np.broadcast_to(camera.eye, d.shape)
    if lens is not None and camera.aperture > 0.0:
        disk = camera.aperture * lens.reshape(-1, 2)
        shift = disk[:, :1] * right + disk[:, 1:] * up  # in the lens plane: depth 0
        start = start + shift
        d = d - shift / camera.focus  # through eye + focus·d: still depth 1
    origins = start + camera.near * d
    return origins, d / np.sqrt((d * d).sum(axis=1))[:, None]


def camera_rays(camera, width: int, height: int, rows: np.ndarray, cols: np.ndarray,
                rng: np.random.Generator | None, jitter=None) -> tuple[np.ndarray, np.ndarray]:
    """Rays through pixels (rows[i], cols[i]) (k,) int: at a uniformly random point of the pixel
    (rng given; or at jitter, (jx, jy) (k,) float64 in [0, 1)) or its centre (rng None, as the
    masks sample), starting on the near plane (CONVENTIONS.md).  Returns origins, unit
    directions as rows (3, k) float64."""
    right, up, back = camera_basis(camera)
    if jitter is not None:
        jx, jy = jitter
    else:
        jx = rng.random(len(rows)) if rng is not None else 0.5
        jy = rng.random(len(rows)) if rng is not None else 0.5
    half_h = math.tan(math.radians(camera.fov_y) / 2.0)
    half_w = half_h * width / height
    sx = ((cols + jx) / width * 2.0 - 1.0) * half_w
    sy = (1.0 - (rows + jy) / height * 2.0) * half_h
    d = sx * right[:, None] + sy * up[:, None] - back[:, None]
    o = np.asarray(camera.eye, np.float64)[:, None] + camera.near * d
    return o, d / np.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
