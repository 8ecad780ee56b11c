"""Direct lighting from emissive surfaces by deterministic quadrature, with the masks' shadows.

An independent witness for the path tracer at depth 1: no random numbers, no path code.  Every
emissive triangle is split by midpoints into 4^k equal-area sub-triangles; their centroids y_m
(area a_m each) become point lights, and the shadow test at each is the reference mask
(`raytrace.masks.shadow_masks`, CONVENTIONS.md "What lit means").  At the visible point x of
each pixel centre, with unit normal n facing the camera,

    L(x) = E(x) + sum_m  lit_m(x) · kd / pi · L_e(y_m) · cos_x cos_y a_m / |x − y_m|^2

(E: the emission seen directly, kd the normalised diffuse albedo of `raytrace.outlook.brdf`;
specular, mirror and glass terms are left out: use it on diffuse scenes).  The midpoint rule's error
is O(4^-k) where the light is fully visible and the order of the sub-triangles' size in penumbrae.
`scene.lights` are ignored: only emissive surfaces light the result.
"""

from __future__ import annotations

import numpy as np

from shadowvol.scene import PointLight, Scene

from raytrace.backends import make_backend
from raytrace.camera import primary_rays
from raytrace.intersect import dot
from raytrace.masks import shadow_masks

from .brdf import normalised_phong
from .radiosity import split_triangles


def emitter_points(scene: Scene, splits: int) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                        np.ndarray]:
    """Quadrature points on the emissive triangles: centroids (m, 3), areas (m,), unit normals
    (m, 3) by winding, emitted radiance (m, 3)."""
    vertices, faces, ids = scene.triangles()
    emission = np.array([o.material.emission for o in scene.objects])[ids]
    e = np.flatnonzero(emission.max(axis=1) > 0.0)
    corners = vertices[faces[e]]
    for _ in range(splits):
        corners = split_triangles(corners)
    per = 4 ** splits
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    area = 0.5 * np.linalg.norm(cross, axis=1)
    return (corners.mean(axis=1), area, cross / (2.0 * area[:, None]),
            np.repeat(emission[e], per, axis=0))


def direct_lighting(scene: Scene, splits: int = 3, backend: str = "embree") -> np.ndarray:
    """(H, W, 3) float64 linear radiance at the pixel centres: see the module docstring."""
    y, area, n_y, radiance = emitter_points(scene, splits)
    vertices, faces, ids = scene.triangles()
    tracer = make_backend(backend, vertices, faces)
    o, d = primary_rays(scene.camera, scene.width, scene.height)
    hits = tracer.closest_hit(o, d)
    image = np.tile(scene.background, (len(o), 1)).astype(np.float64)
    h = np.flatnonzero(hits.tri >= 0)
    obj = ids[hits.tri[h]]
    kd, _ = normalised_phong(np.array([ob.material.diffuse for ob in scene.objects]),
                             np.array([ob.material.specular for ob in scene.objects]))
    emission = np.array([ob.material.emission for ob in scene.objects])
    x = o[h] + hits.t[h, None] * d[h]
    n = tracer.normals[hits.tri[h]]
    n = np.where((dot(n, d[h]) < 0.0)[:, None], n, -n)  # facing the camera
    lit, _ = shadow_masks(scene.replace(lights=[PointLight(position=p) for p in y]),
                          backend=backend)
    lit = lit.reshape(len(y), -1)[:, h]
    colour = emission[obj].copy()
    for m in range(len(y)):
        to_y = y[m] - x
        r2 = dot(to_y, to_y)
        w = to_y / np.sqrt(r2)[:, None]
        g = np.maximum(dot(n, w), 0.0) * np.abs(dot(w, n_y[m])) * area[m] / r2
        colour += (lit[m] * g)[:, None] * kd[obj] / np.pi * radiance[m]
    image[h] = colour
    return image.reshape(scene.height, scene.width, 3)
