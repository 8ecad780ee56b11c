"""Intrinsic layers from the ray tracer's direct light (docs/CONVENTIONS.md, "Intrinsic
layers"): per pixel the diffuse reflectance `albedo`, the `ambient` term, and per light its
unshadowed contribution `direct` and its contribution with its shadows `direct_shadowed`, and
`shadow_free`, the image with every light's shadows off.

Everything is `raytrace.outlook.whitted`'s depth-0 shading (`render(scene, max_depth=0)`, the
direct light the rasterizer draws): the same pixel-centre primary rays, the same hit points,
base colours (`World.base_colour`: textures and vertex colours) and shadow rays
(`whitted.shadow_rays`), the same Phong term per hard light sample (`whitted.local_colour`),
summed in float64 and rounded once to float32.  An area light is its samples: its `direct` is
the sum of its samples' terms, its `direct_shadowed` the sum over the samples that reach the
point.  Where nothing is hit, `ambient` holds `scene.background` (the image's value there) and
the other layers 0, so that at every pixel, up to float32 rounding,

    image = ambient + Σ_i direct_shadowed[i]      shadow_free = ambient + Σ_i direct[i]
"""

from __future__ import annotations

import numpy as np

from shadowvol.frame import LAYERS, check_outputs
from shadowvol.scene import Scene, emission_cosine, hard_lights

from raytrace.camera import primary_rays
from raytrace.intersect import dot, reflect

from .whitted import World, shadow_rays, surface_frame


def layers(scene: Scene, outputs=LAYERS, backend: str = "embree") -> dict[str, np.ndarray]:
    """The intrinsic layers `outputs` (names from `shadowvol.frame.LAYERS`; default all) of
    `scene`, by name, float32: albedo, ambient, shadow_free (H, W, 3); direct,
    direct_shadowed (L, H, W, 3).  backend : "embree" or "numpy"."""
    outputs = check_outputs(outputs, LAYERS)
    H, W, L = scene.height, scene.width, len(scene.lights)
    world = World(scene, backend)
    o, d = primary_rays(scene.camera, W, H, slice(0, H))
    t, obj, geo_n, tri = world.hits(o, d)
    h = np.flatnonzero(obj >= 0)
    o, d, t, obj, geo_n, tri = o[h], d[h], t[h], obj[h], geo_n[h], tri[h]
    p, _, n = surface_frame(o, d, t, geo_n)
    base = world.base_colour(obj, tri, p)
    ka, kd = world.ka[obj], world.kd[obj]
    if base is not None:
        ka, kd = ka * base, kd * base
    out = {}
    if "albedo" in outputs:
        out["albedo"] = _pixels(H, W, h, kd)
    if "ambient" in outputs:
        out["ambient"] = _pixels(H, W, h, ka * scene.ambient, background=scene.background)
    wants_light = {"direct", "direct_shadowed", "shadow_free"} & set(outputs)
    if not wants_light:
        return out
    direct = np.zeros((L, len(h), 3))
    shadowed = np.zeros((L, len(h), 3))
    view = -d
    for i, light in enumerate(scene.lights):
        for sample in hard_lights(light):
            term, visible = _sample_term(world, sample, p, n, view, obj, kd)
            direct[i] += term
            shadowed[i] += term * visible[:, None]
    if "direct" in outputs:
        out["direct"] = np.stack([_pixels(H, W, h, direct[i]) for i in range(L)])
    if "direct_shadowed" in outputs:
        out["direct_shadowed"] = np.stack([_pixels(H, W, h, shadowed[i]) for i in range(L)])
    if "shadow_free" in outputs:
        # the image with every light's shadows off: ambient + Σ direct, summed in float64 in
        # the order local_colour sums them, rounded once
        out["shadow_free"] = _pixels(H, W, h, ka * scene.ambient + direct.sum(axis=0),
                                     background=scene.background)
    return {name: out[name] for name in outputs}


def _sample_term(world: World, light, p, n, view, obj, kd) -> tuple[np.ndarray, np.ndarray]:
    """One hard light (or area-light sample) at points p (k, 3): its Phong term (k, 3) float64
    where it faces the point and its cone holds it (0 elsewhere), exactly as
    `whitted.local_colour` adds it, and (k,) bool where it also reaches the point."""
    rays = shadow_rays(world, light, p, n, obj)
    lit = rays.facing & rays.in_cone
    c = np.flatnonzero(lit)
    l, n_dot_l = rays.to_light, rays.n_dot_l
    r = reflect(-l[c], n[c])
    r_dot_v = np.maximum(dot(r, view[c]), 0.0)
    o = obj[c]
    term = np.zeros((len(p), 3))
    term[c] = ((kd[c] * n_dot_l[c, None] + world.ks[o] * (r_dot_v ** world.shininess[o])[:, None])
               * light.radiance * np.reshape(emission_cosine(light, l[c]), (-1, 1)))
    return term, rays.visible


def _pixels(H: int, W: int, h: np.ndarray, values: np.ndarray, background=None) -> np.ndarray:
    """(H, W, 3) float32: `values` (k, 3) float64 at the flat pixels h, 0 (or `background`)
    elsewhere."""
    out = np.zeros((H * W, 3))
    if background is not None:
        out[:] = background
    out[h] = values
    return out.reshape(H, W, 3).astype(np.float32)
