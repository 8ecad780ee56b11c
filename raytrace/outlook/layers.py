"""Intrinsic layers from the ray tracer's direct light (docs/CONVENTIONS.md, "Intrinsic
layers"): per pixel the diffuse reflectance `albedo`, the `ambient` term, and per light its
unshadowed contribution `direct` and its contribution with its shadows `direct_shadowed`, and
`shadow_free`, the image with every light's shadows off.

Everything is `raytrace.outlook.whitted`'s depth-0 shading (`render(scene, max_depth=0)`, the
direct light the rasterizer draws): the same pixel-centre primary rays, the same hit points,
base colours (`World.base_colour`: textures and vertex colours) and shadow rays
(`whitted.shadow_rays`), the same Phong term per hard light sample (`whitted.local_colour`),
summed in float64 and rounded once to float32 (`shadow_free` in local_colour's own order:
the `max_depth=0` render with every light's shadows off, bit for bit).  An area light is its samples: its `direct` is
the sum of its samples' terms, its `direct_shadowed` the sum over the samples that reach the
point.  Where nothing is hit, `ambient` holds `scene.background` (the image's value there) and
the other layers 0, so that at every pixel, up to float32 rounding,

    image = ambient + Σ_i direct_shadowed[i]      shadow_free = ambient + Σ_i direct[i]
"""

from __future__ import annotations

import numpy as np

from shadowvol.frame import LAYERS, check_outputs, shape
from shadowvol.scene import Scene, emission_cosine, hard_lights

from raytrace.camera import primary_rays
from raytrace.intersect import dot, reflect

from .whitted import TILE_RAYS, World, shadow_rays, surface_frame


def layers(scene: Scene, outputs=LAYERS, backend: str = "embree") -> dict[str, np.ndarray]:
    """The intrinsic layers `outputs` (names from `shadowvol.frame.LAYERS`; default all) of
    `scene`, by name, float32: albedo, ambient, shadow_free (H, W, 3); direct,
    direct_shadowed (L, H, W, 3).  backend : "embree" or "numpy".  Traced in tiles of rows
    (`whitted.TILE_RAYS` rays), as `whitted.render` is."""
    outputs = check_outputs(outputs, LAYERS)
    H, W, L = scene.height, scene.width, len(scene.lights)
    world = World(scene, backend)
    out = {name: np.zeros(shape(name, L, H, W, flat=True), np.float32) for name in outputs}
    for name in {"ambient", "shadow_free"} & set(outputs):
        out[name][:] = scene.background   # what the image holds where nothing is hit
    rows_per_tile = max(1, TILE_RAYS // W)
    for y in range(0, H, rows_per_tile):
        _tile(world, scene, slice(y, min(y + rows_per_tile, H)), out)
    return {name: out[name].reshape(shape(name, L, H, W)) for name in outputs}


def _tile(world: World, scene: Scene, rows: slice, out: dict[str, np.ndarray]) -> None:
    """The layers `out` asks for (flat pixels, float32) at the image rows `rows`: float64
    sums, rounded once."""
    W, L = scene.width, len(scene.lights)
    o, d = primary_rays(scene.camera, W, scene.height, rows)
    t, obj, geo_n, tri = world.hits(o, d)
    h = np.flatnonzero(obj >= 0)
    pixel = rows.start * W + h
    o, d, t, obj, geo_n, tri = o[h], d[h], t[h], obj[h], geo_n[h], tri[h]
    p, _, n = surface_frame(o, d, t, geo_n)
    base = world.base_colour(obj, tri, p)
    ka, kd = world.ka[obj], world.kd[obj]
    if base is not None:
        ka, kd = ka * base, kd * base
    if "albedo" in out:
        out["albedo"][pixel] = kd
    if "ambient" in out:
        out["ambient"][pixel] = ka * scene.ambient
    if not {"direct", "direct_shadowed", "shadow_free"} & set(out):
        return
    direct = np.zeros((L, len(h), 3))
    shadowed = np.zeros((L, len(h), 3))
    # the image with every light's shadows off, summed as `whitted.local_colour` sums it
    # (ambient, then each sample in turn; adding 0 where a sample does not face is exact):
    # the shadow-free render's pixels bit for bit
    free = ka * scene.ambient
    for i, light in enumerate(scene.lights):
        for sample in hard_lights(light):
            term, visible = _sample_term(world, sample, p, n, -d, obj, kd)
            direct[i] += term
            shadowed[i] += term * visible[:, None]
            free += term
    if "direct" in out:
        out["direct"][:, pixel] = direct
    if "direct_shadowed" in out:
        out["direct_shadowed"][:, pixel] = shadowed
    if "shadow_free" in out:
        out["shadow_free"][pixel] = free


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
