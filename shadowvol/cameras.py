"""The camera matrices and light arrays stored with every frame, computed once, GL-free.

Both renderers return these and every mask file holds them (docs/CONVENTIONS.md, "Camera
matrices"), so that a frame can be unprojected, matched to another view or fed to a vision
pipeline without knowing our look-at camera:

* `K` (3, 3): pixels.  A point at camera coordinates (X, Y, Z) (OpenCV: x right, y down,
  z forward) lands at u = fx·X/Z + cx, v = fy·Y/Z + cy, where pixel (x, y) covers
  [x, x+1) × [y, y+1) and is sampled at its centre (x + 0.5, y + 0.5): so the principal point
  is the image centre (W/2, H/2) (COLMAP's and nerfstudio's convention; OpenCV's, which puts
  pixel centres on whole numbers, is cx − 0.5, cy − 0.5).
* `world_to_camera` (4, 4): world -> OpenCV camera coordinates (x right, y down, z forward).
* `camera_to_world` (4, 4): OpenGL camera (x right, y up, looking down −z) -> world, as
  nerfstudio's transforms.json stores `transform_matrix`.  It is NOT the inverse of
  `world_to_camera`: the two differ by diag(1, −1, −1, 1), the flip between the conventions.
* `light_position` (L, 4): each light as a homogeneous point, (position, 1), or for a
  directional light (−direction, 0), the point at infinity it comes from; an area light's
  centre (its samples are the mask file's `light_samples_<i>`).
* `light_direction` (L, 3): the direction a directional light travels, a spot light's axis, a
  rect or disk light's normal (the side it emits to), (0, 0, 0) for a point or sphere light.

All float64.  A look-at camera's basis is the look-at basis of CONVENTIONS.md ("Camera and
pixels") and its K has fx = fy and the principal point at the image centre; a camera given by
matrices (`Camera.fx` ... `Camera.camera_to_world`) has the ones it was given, returned
unchanged, so that a frame's K and camera_to_world, read back as its camera, give the same
frame bit for bit.

`frame_origin` is the origin of the float32 frame both renderers draw and trace in (the eye):
the one definition, so that both round the same float64 differences to the same float32
triangles (docs/CONVENTIONS.md, "The float32 frame").
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from shadowvol.scene import AreaLight, Camera, DirectionalLight, Scene, SpotLight

# OpenGL camera axes (x right, y up, z back) -> OpenCV camera axes (x right, y down, z forward)
GL_TO_CV = np.diag([1.0, -1.0, -1.0, 1.0])


class Calibration(NamedTuple):
    """The camera matrices and light arrays of one frame (see the module), float64."""

    K: np.ndarray
    world_to_camera: np.ndarray
    camera_to_world: np.ndarray
    light_position: np.ndarray
    light_direction: np.ndarray

    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays by their file names (`shadowvol.frame.save_masks`)."""
        return self._asdict()


def frame_origin(camera: Camera) -> np.ndarray:
    """(3,) float64: the origin of the float32 frame of a frame seen by `camera`, its eye.
    Both renderers express every position as float64 world minus this, rounded to float32
    once, so a world far from its origin is drawn and traced as exactly as one at it."""
    return np.array(camera.eye, dtype=np.float64)


def look_at_basis(camera: Camera) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The camera's orthonormal basis in world space: right (x), up (y), back (z), each (3,)
    float64; the camera looks down −back.  A matrix camera's: the columns of its
    camera_to_world, as given."""
    if camera.matrix_form:
        m = camera.camera_to_world
        return m[:3, 0].copy(), m[:3, 1].copy(), m[:3, 2].copy()
    back = camera.eye - camera.target
    back = back / np.linalg.norm(back)
    right = np.cross(camera.up, back)
    right = right / np.linalg.norm(right)
    return right, np.cross(back, right), back


def pinhole(camera: Camera, width: int, height: int) -> tuple[float, float, float, float]:
    """(fx, fy, cx, cy) of a W × H image in pixels (see the module): a look-at camera's
    square pixels, fx = fy = (H / 2) / tan(fov_y / 2), principal point (W / 2, H / 2); a
    matrix camera's own."""
    if camera.matrix_form:
        return camera.fx, camera.fy, camera.cx, camera.cy
    f = (height / 2.0) / math.tan(math.radians(camera.fov_y) / 2.0)
    return f, f, width / 2.0, height / 2.0


def intrinsics(camera: Camera, width: int, height: int) -> np.ndarray:
    """K (3, 3) float64 of a W × H image (see the module and `pinhole`)."""
    fx, fy, cx, cy = pinhole(camera, width, height)
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def camera_to_world(camera: Camera) -> np.ndarray:
    """(4, 4) float64: OpenGL camera coordinates -> world (columns right, up, back, eye); a
    matrix camera's own, as given."""
    if camera.matrix_form:
        return camera.camera_to_world.copy()
    m = np.eye(4)
    m[:3, :3] = np.column_stack(look_at_basis(camera))
    m[:3, 3] = camera.eye
    return m


def world_to_camera(camera: Camera) -> np.ndarray:
    """(4, 4) float64: world -> OpenCV camera coordinates (rows right, −up, −back)."""
    right, up, back = look_at_basis(camera)
    r = np.stack([right, -up, -back])
    m = np.eye(4)
    m[:3, :3] = r
    m[:3, 3] = -r @ camera.eye
    return m


def light_arrays(lights) -> tuple[np.ndarray, np.ndarray]:
    """light_position (L, 4) and light_direction (L, 3), float64 (see the module)."""
    def position(light):
        return np.append(light.center, 1.0) if isinstance(light, AreaLight) else light.homogeneous

    def direction(light):
        if isinstance(light, (DirectionalLight, SpotLight)):
            return light.direction
        if isinstance(light, AreaLight) and light.normal is not None:
            return light.normal
        return np.zeros(3)

    return (np.array([position(lt) for lt in lights], np.float64).reshape(-1, 4),
            np.array([direction(lt) for lt in lights], np.float64).reshape(-1, 3))


def calibration(scene: Scene) -> Calibration:
    """The Calibration of `scene`'s camera, image size and lights."""
    position, direction = light_arrays(scene.lights)
    return Calibration(intrinsics(scene.camera, scene.width, scene.height),
                       world_to_camera(scene.camera), camera_to_world(scene.camera),
                       position, direction)


def project(K: np.ndarray, world_to_camera: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(n, 3) world points -> (n, 2) float64 continuous pixel coordinates (u, v): pixel
    (x, y) is floor(u), floor(v).  Points behind the camera give meaningless values."""
    cam = points @ world_to_camera[:3, :3].T + world_to_camera[:3, 3]
    uvw = cam @ K.T
    return uvw[:, :2] / uvw[:, 2:3]


def unproject(K: np.ndarray, camera_to_world: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """Eye-space depth (H, W) -> (H, W, 3) float64 world points of the pixel centres (nan
    where depth is inf).  Uses only K and the OpenGL camera_to_world, as a dataset user
    would."""
    H, W = depth.shape
    u = np.arange(W) + 0.5
    v = np.arange(H) + 0.5
    d = np.where(np.isfinite(depth), depth, np.nan).astype(np.float64)
    x = (u[None, :] - K[0, 2]) / K[0, 0] * d
    y = (v[:, None] - K[1, 2]) / K[1, 1] * d
    cam_gl = np.stack([x, -y, -d], axis=-1)  # OpenCV (x, y, d) -> OpenGL (x, −y, −d)
    return cam_gl @ camera_to_world[:3, :3].T + camera_to_world[:3, 3]
