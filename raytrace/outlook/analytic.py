"""`raytrace render --integrator analytic`: the direct light with the diffuse term of every area
light computed, not sampled (issue 41, step 2).

The image is Whitted's direct light (`raytrace.outlook.whitted`, max_depth 0: pixel centres, no
reflection or refraction generations), with one term changed: the diffuse light of a rect, disk
or polygon light.  Whitted (and the path tracer's next-event estimate of `scene.lights`) shade
an area light as its N samples, sample s adding

    kd · max(n·l_s, 0) · cos_light,s · color · intensity / N      (visible samples; no fall-off)

(docs/CONVENTIONS.md, "Area lights"), so as N grows (samples evenly spread by area) the sum
tends to

    kd · color · intensity · D,   D = (1 / area) ∫_visible cos(at p) cos(at the light) dA,

the emitter's convention being "color · intensity per unit of the light's cosine-weighted
area fraction, without the inverse-square fall-off".  D is `raytrace.exact_soft`'s
`ExactVisibility.direct`: the visible region (the light less the union of the occluders'
shadows, exact), integrated over its boundary (`raytrace.polygons.direct_measure`).  Were the
emitter physical (radiance L, with fall-off), the same region would give kd/π · π L ·
`irradiance_exact` instead; this project's sampled lights are not, and the analytic image is
their limit.  The specular (Phong) term of area lights stays the samples' sum, as in Whitted;
ambient and hard lights are Whitted's.  No random numbers: the same scene gives the same image,
bit for bit.  Sphere lights have no exact visibility (refused, SceneError).
"""

from __future__ import annotations

import copy

import numpy as np

from shadowvol.scene import AreaLight, Scene

from raytrace.camera import primary_rays
from raytrace.exact_soft import check_exact, exact_visibility

from .whitted import World, local_colour, surface_frame

__all__ = ["render"]


def render(scene: Scene, backend: str = "embree") -> np.ndarray:
    """(H, W, 3) float64 linear RGB, row 0 at the top: see the module.  SceneError for a
    sphere light; MissingExtra without shapely where an area light needs it."""
    check_exact(scene)
    H, W = scene.height, scene.width
    area = [i for i, lt in enumerate(scene.lights) if isinstance(lt, AreaLight)]
    world = World(scene, backend)
    o, d = primary_rays(scene.camera, W, H)
    t, obj, geo_n, tri = world.hits(o, d)
    image = np.tile(np.asarray(scene.background, np.float64), (H * W, 1))
    h = np.flatnonzero(obj >= 0)
    if len(h) == 0:
        return image.reshape(H, W, 3)
    obj, tri = obj[h], tri[h]
    p, _, n = surface_frame(o[h], d[h], t[h], geo_n[h])
    base = world.base_colour(obj, tri, p)
    # ambient and hard lights: Whitted's local term
    hard = scene.replace(lights=tuple(lt for i, lt in enumerate(scene.lights) if i not in area))
    colour = local_colour(world, hard, p, n, -d[h], obj, base)
    if area:
        # area lights' specular: their samples, as Whitted (the diffuse albedo set to 0)
        specular = copy.copy(world)
        specular.kd = np.zeros_like(world.kd)
        only = scene.replace(lights=tuple(scene.lights[i] for i in area),
                             ambient=np.zeros(3))
        colour += local_colour(specular, only, p, n, -d[h], obj, None)
        # and their diffuse: the exact limit of the samples' sum
        exact = exact_visibility(scene.replace(lights=only.lights), backend, direct=True)
        kd = world.kd[obj] if base is None else world.kd[obj] * base
        for k, i in enumerate(area):
            colour += kd * scene.lights[i].radiance * exact.direct[k].reshape(-1)[h][:, None]
    image[h] = colour
    return image.reshape(H, W, 3)
