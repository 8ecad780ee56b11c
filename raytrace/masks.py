"""Reference shadow masks, exactly as CONVENTIONS.md ("What lit means") defines them.

For light i and pixel p, lit[i, p] is True when geometry is visible at p's centre, its geometric
(face) normal flipped to face the camera points toward the light (n·l > 0), a spot light's cone
contains the point, and no geometry lies between the point and the light.  Everything is traced
on the scene's triangles (`Scene.triangles()`), the same ones the rasterizer draws: the exact
sphere is for images only.
"""

from __future__ import annotations

import numpy as np

from shadowvol.scene import DirectionalLight, PointLight, Scene, SpotLight

from .backends import TriangleBackend, make_backend
from .camera import primary_rays
from .intersect import dot
from .tolerances import surface_offset


def scene_backend(scene: Scene, backend: str = "embree") -> TriangleBackend:
    """A triangle backend holding all of the scene's triangles (for `shadow_masks`)."""
    vertices, faces, _ = scene.triangles()
    return make_backend(backend, vertices, faces)


def shadow_masks(scene: Scene, backend: str | TriangleBackend = "embree"
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The reference masks of `scene`.

    backend : "embree", "numpy", or a backend already built by `scene_backend(scene, ...)`
              (the benchmark reuses one; any other triangles would give wrong masks).
    Returns lit : (L, H, W) bool, lights in scene order, and coverage : (H, W) bool; row 0 at
    the top.
    """
    tracer = scene_backend(scene, backend) if isinstance(backend, str) else backend
    H, W = scene.height, scene.width
    origins, directions = primary_rays(scene.camera, W, H)
    hits = tracer.closest_hit(origins, directions)
    coverage = hits.tri >= 0
    lit = np.zeros((len(scene.lights), H * W), bool)
    idx = np.flatnonzero(coverage)
    if len(idx) and scene.lights:
        view = directions[idx]
        point = origins[idx] + hits.t[idx, None] * view
        normal = tracer.normals[hits.tri[idx]]
        normal *= np.where(dot(normal, view) > 0.0, -1.0, 1.0)[:, None]  # face the camera
        # Shadow rays start off the surface on the camera's side, which is the light's side
        # wherever n·l > 0 (the only points that need one).
        start = point + surface_offset(scene) * normal
        for i, light in enumerate(scene.lights):
            lit[i, idx] = _lit(tracer, light, point, normal, start)
    return lit.reshape(-1, H, W), coverage.reshape(H, W)


def _lit(tracer: TriangleBackend, light, point: np.ndarray, normal: np.ndarray,
         start: np.ndarray) -> np.ndarray:
    """(k,) bool: which surface points (k, 3) with camera-facing unit normals (k, 3) the light
    reaches; shadow rays leave from `start` (k, 3)."""
    if isinstance(light, DirectionalLight):
        toward = -light.direction
        candidate = normal @ toward > 0.0
        lit = candidate.copy()
        # Unbounded: anything anywhere along the ray toward a directional light blocks it.
        lit[candidate] = ~tracer.occluded(start[candidate],
                                          np.broadcast_to(toward, start[candidate].shape))
        return lit
    if not isinstance(light, (PointLight, SpotLight)):
        raise TypeError(f"not a light: {type(light).__name__}")
    to_light = light.position - point
    candidate = dot(normal, to_light) > 0.0
    if isinstance(light, SpotLight):
        # Inside the cone: cos(angle between the spot's axis and the point) >= cos_cutoff.
        axis_dot = -(to_light @ light.direction)
        candidate &= axis_dot >= light.cos_cutoff * np.linalg.norm(to_light, axis=1)
    lit = candidate.copy()
    s = start[candidate]
    # Bounded: the segment from the start to the light, direction not normalised, so tmax = 1.
    lit[candidate] = ~tracer.occluded(s, light.position - s, 1.0)
    return lit
