"""Primary rays, exactly as CONVENTIONS.md defines the camera and the pixels.

The basis and the intrinsics are computed here from the `Camera` fields alone (not borrowed
from the rasterizer: the ray tracer is an independent witness).  OpenGL style: the camera looks
down its -z axis, x to the right, y up.  A look-at camera's basis comes from eye, target and
up, its intrinsics from fov_y (square pixels, the principal point at the image centre); a
camera given by matrices has them as data: the columns of `camera_to_world` and fx, fy, cx, cy.
The ray through the point (u, v) of the image (pixel (x, y) covers [x, x+1) x [y, y+1), row 0
at the top) has, at eye-space depth 1, the direction

    right · (u - cx) / fx + up · (cy - v) / fy - back

which is the pixel K maps it to (docs/CONVENTIONS.md, "Camera matrices").
"""

from __future__ import annotations

import math

import numpy as np


def camera_basis(camera) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The camera's orthonormal basis in world space: right (x), up (y), back (z), each (3,)
    float64.  The view direction is -back.  A matrix camera's: its camera_to_world's
    columns."""
    if camera.camera_to_world is not None:
        m = np.asarray(camera.camera_to_world, np.float64)
        return m[:3, 0].copy(), m[:3, 1].copy(), m[:3, 2].copy()
    back = camera.eye - camera.target
    back = back / np.linalg.norm(back)
    right = np.cross(camera.up, back)
    right = right / np.linalg.norm(right)
    up = np.cross(back, right)
    return right, up, back


def pixel_focal(camera, width: int, height: int) -> tuple[float, float, float, float]:
    """(fx, fy, cx, cy) in pixels of a W x H image: a matrix camera's own; a look-at camera's
    fx = fy = (H / 2) / tan(fov_y / 2), cx = W / 2, cy = H / 2 (CONVENTIONS.md)."""
    if camera.camera_to_world is not None:
        return float(camera.fx), float(camera.fy), float(camera.cx), float(camera.cy)
    f = (height / 2.0) / math.tan(math.radians(camera.fov_y) / 2.0)
    return f, f, width / 2.0, height / 2.0


class RayGrid:
    """The primary rays of a W x H image, factored: the direction through pixel (x, y)'s centre,
    scaled to eye-space depth 1, is  col[:, x] + row[:, y]  with

        col[:, x] = right · (x + 0.5 - cx) / fx − back     (3, W)
        row[:, y] = up · (cy − (y + 0.5)) / fy             (3, H)

    and the ray starts on the near plane at  eye + near · direction.  Stored component-major
    (3, n) in `dtype` because numpy is fast on long contiguous rows (the masks' hot path).
    """

    def __init__(self, camera, width: int, height: int, dtype=np.float64):
        right, up, back = camera_basis(camera)
        fx, fy, cx, cy = pixel_focal(camera, width, height)
        x = (np.arange(width) + 0.5 - cx) / fx
        y = (cy - (np.arange(height) + 0.5)) / fy
        self.width, self.height, self.dtype = width, height, dtype
        self.eye = camera.eye.astype(dtype)
        self.near = dtype(camera.near)
        self.col = (right[:, None] * x - back[:, None]).astype(dtype)
        self.row = (up[:, None] * y).astype(dtype)

    def directions(self, rows: slice | None = None) -> np.ndarray:
        """(3, R*W) directions of eye-space depth 1 for the image rows `rows` (default all),
        row-major pixel order within them."""
        r = self.row[:, rows or slice(None)]
        return (r[:, :, None] + self.col[:, None, :]).reshape(3, -1)

    def origins(self, directions: np.ndarray) -> np.ndarray:
        """(3, n) ray starts on the near plane for directions (3, n) of depth 1."""
        return self.eye[:, None] + self.near * directions

    def farthest_start(self) -> float:
        """How far from the eye a ray starts, the farthest (at an image corner: a direction's
        col and row parts are orthogonal), a little more for the roundings."""
        most = (self.col.astype(np.float64) ** 2).sum(axis=0).max() + \
            (self.row.astype(np.float64) ** 2).sum(axis=0).max()
        return float(self.near * np.sqrt(most) * (1 + 2.0 ** -20))


def primary_rays(camera, width: int, height: int, rows: slice | None = None,
                 dtype=np.float64, unit: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """One ray per pixel centre, starting where it crosses the near plane.

    rows  : the image rows to make rays for (default: all), row 0 at the top.
    dtype : float64, or float32.
    unit  : normalise the directions (then t along a ray is a distance); if False, each
            direction has eye-space depth 1 (its component along the view axis is 1).
    Returns origins : (R*W, 3) and directions : (R*W, 3) of `dtype`, in row-major pixel order
    (index = row * W + x within `rows`).

    In eye space the ray through the pixel centre (u, v) has direction ((u - cx) / fx,
    (cy - v) / fy, -1) (the module); scaled by `near` it reaches the near plane (eye-space
    depth == near, a plane, not a sphere), which is where the ray starts: geometry nearer than
    that is clipped, as in the rasterizer.
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
              corner (x right, y down); 0.5 is the centre.
    lens    : (P, S, 2) float64 points of the unit disk, scaled by `camera.aperture` (the
              lens radius) along right and up; None or aperture 0: a pinhole.
    Returns origins, unit directions : (P*S, 3) float64, sample-minor (the i-th pixel's
    samples at i*S .. i*S + S - 1).  A lens ray aims where the pinhole ray of the same pixel
    position meets the plane of focus (eye-space depth `camera.focus`): that plane is sharp.
    Every ray starts on the near plane.
    """
    right, up, back = camera_basis(camera)
    fx, fy, cx, cy = pixel_focal(camera, width, height)
    px = (pixels % width)[:, None] + offsets[..., 0]
    py = (pixels // width)[:, None] + offsets[..., 1]
    x = ((px - cx) / fx).reshape(-1)
    y = ((cy - py) / fy).reshape(-1)
    d = up * y[:, None] + (right * x[:, None] - back)  # depth 1
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
    fx, fy, cx, cy = pixel_focal(camera, width, height)
    sx = (cols + jx - cx) / fx
    sy = (cy - (rows + jy)) / fy
    d = sx * right[:, None] + sy * up[:, None] - back[:, None]
    o = np.asarray(camera.eye, np.float64)[:, None] + camera.near * d
    return o, d / np.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
