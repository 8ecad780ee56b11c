"""Builders for scene objects: primitives, meshes and transforms.

Used by the scene-file loader and by code and tests that build scenes directly, e.g.

    scene = Scene(camera=Camera(eye=[0, 2, 6], target=[0, 0, 0]),
                  objects=[plane("floor", size=[10, 10]), sphere("ball", [0, 1, 0], 1.0)],
                  lights=[PointLight([2, 5, 2])])
"""

from __future__ import annotations

import math

import numpy as np

from shadowvol.planes import default_plane_axes
from shadowvol.checks import RIGID_TOLERANCE
from shadowvol.scene import (
    Material,
    Object,
    Parallelogram,
    SceneError,
    Sphere,
    frozen,
    num,
    similarity_matrix,
    unit,
    vec,
)

DEFAULT_SPHERE_SUBDIVISIONS = 3  # icosphere level: 1280 triangles


class Transform:
    """Scale, then rotate (Euler angles in degrees about x, then y, then z, fixed axes), then
    translate: `matrix` is the (4, 4) float64 M = T @ Rz @ Ry @ Rx @ S.  Or a given (4, 4)
    `matrix`, a similarity (a rotation, one positive scale, a translation; no shear, no mirror:
    `checks.similarity_matrix`), instead of the three.

    `pose` is the rigid part (T @ R: the object's pose) and `scale` the (3,) scale, which
    belongs to the model: `matrix = pose @ diag(scale)`, exactly for the three keys."""

    def __init__(self, scale=1.0, rotation=(0.0, 0.0, 0.0), translation=(0.0, 0.0, 0.0),
                 matrix=None):
        if matrix is not None:
            self.matrix, s = similarity_matrix(matrix, "matrix")
            if abs(s - 1.0) <= RIGID_TOLERANCE:
                s = 1.0   # a rotation's determinant is 1 only up to rounding: no scale
            self.scale = vec([s, s, s], "scale")
            self.rotation = None   # not given as angles
            self.translation = vec(self.matrix[:3, 3], "translation")
            pose = self.matrix.copy()
            pose[:3, :3] /= s
            self.pose = frozen(pose)
            return
        if np.ndim(scale) == 0:
            scale = [num(scale, "scale", low=0.0, low_open=True)] * 3
        self.scale = vec(scale, "scale", positive=True)
        self.rotation = vec(rotation, "rotation")
        self.translation = vec(translation, "translation")
        rx, ry, rz = np.radians(self.rotation)
        cx, sx, cy, sy, cz, sz = (math.cos(rx), math.sin(rx), math.cos(ry), math.sin(ry),
                                  math.cos(rz), math.sin(rz))
        Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
        Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
        Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
        m = np.eye(4)
        m[:3, :3] = Rz @ Ry @ Rx @ np.diag(self.scale)
        m[:3, 3] = self.translation
        self.matrix = m
        pose = np.eye(4)
        pose[:3, :3] = Rz @ Ry @ Rx
        pose[:3, 3] = self.translation
        self.pose = frozen(pose)

    @property
    def is_identity(self) -> bool:
        return bool(np.array_equal(self.matrix, np.eye(4)))

    @property
    def is_uniform(self) -> bool:
        return bool(np.ptp(self.scale) <= 1e-12 * self.scale.max())

    def points(self, p: np.ndarray) -> np.ndarray:
        """(n, 3) -> (n, 3): transformed positions."""
        return p @ self.matrix[:3, :3].T + self.matrix[:3, 3]

    def vectors(self, v: np.ndarray) -> np.ndarray:
        """(n, 3) -> (n, 3): transformed direction vectors (no translation)."""
        return v @ self.matrix[:3, :3].T


IDENTITY = Transform()


def _pose(transform: Transform) -> np.ndarray | None:
    """An object's pose from its transform: the rigid part, None for the identity."""
    return None if transform.is_identity else transform.pose


def mesh(name: str, vertices, faces, material: Material | None = None,
         transform: Transform = IDENTITY, uv=None, colors=None) -> Object:
    """An object from a triangle mesh, kept exactly as given (no welding, no reordering);
    `uv`, `colors`: per-vertex texture coordinates and linear colours (`Object`)."""
    v = np.asarray(vertices, dtype=np.float64)
    if v.ndim == 2 and v.shape[1] == 3 and np.isfinite(v).all():
        v = transform.points(v)
    # else: Object rejects the vertices, naming them as given (not as the transform mangled them)
    return Object(name, v, np.asarray(faces), material or Material(), uv=uv, colors=colors,
                  pose=_pose(transform))


def sphere(name: str, center, radius: float, material: Material | None = None,
           transform: Transform = IDENTITY,
           subdivisions: int = DEFAULT_SPHERE_SUBDIVISIONS) -> Object:
    """A sphere: exact for the ray tracer, an icosphere for the rasterizer and the masks.
    The transform must scale uniformly (a sphere stays a sphere)."""
    center = vec(center, "center")
    radius = num(radius, "radius", low=0.0, low_open=True)
    if not transform.is_uniform:
        raise SceneError("transform.scale", "a sphere needs a uniform scale")
    if isinstance(subdivisions, bool) or not isinstance(subdivisions, int) or not 0 <= subdivisions <= 7:
        raise SceneError("subdivisions", f"must be a whole number 0..7, got {subdivisions!r}")
    import trimesh  # heavy: imported when a sphere is first tessellated

    ico = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    local = np.asarray(ico.vertices) * radius + center
    world_center = transform.points(center[None])[0]
    exact = Sphere(world_center, radius * float(transform.scale[0]))
    return Object(name, transform.points(local), np.asarray(ico.faces), material or Material(),
                  analytic=exact, pose=_pose(transform))


def plane(name: str, point=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0), size=(10.0, 10.0),
          material: Material | None = None, transform: Transform = IDENTITY) -> Object:
    """A finite plane: the rectangle of `size` = (along u, along v) centred on `point`, as two
    triangles, with its exact parallelogram for the ray tracer."""
    point = vec(point, "point")
    normal = unit(vec(normal, "normal"), "normal")
    w, h = vec(size, "size", n=2, positive=True)
    u, v = default_plane_axes(normal)
    corners = np.array([point - u * w / 2 - v * h / 2, point + u * w / 2 - v * h / 2,
                        point + u * w / 2 + v * h / 2, point - u * w / 2 + v * h / 2])
    world = transform.points(corners)
    exact = Parallelogram(world[0], world[1] - world[0], world[3] - world[0])
    return Object(name, world, np.array([[0, 1, 2], [0, 2, 3]]), material or Material(),
                  analytic=exact, pose=_pose(transform))


def box(name: str, center=(0.0, 0.0, 0.0), size=(1.0, 1.0, 1.0),
        material: Material | None = None, transform: Transform = IDENTITY) -> Object:
    """An axis-aligned box (before the transform) of `size` centred on `center`: 12 triangles,
    closed, wound outward."""
    center = vec(center, "center")
    size = vec(size, "size", positive=True)
    import trimesh  # heavy: imported when a box is first built

    b = trimesh.creation.box(extents=size)
    return Object(name, transform.points(np.asarray(b.vertices) + center), np.asarray(b.faces),
                  material or Material(), pose=_pose(transform))
