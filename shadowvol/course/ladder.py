"""The lecture's ladder as one picture: the same scene and camera through each compromise made
to solve the rendering equation

    L(x, wo) = Le(x, wo) + ∫ fr(x, wi, wo) L(x', −wi) V(x, x') cos(theta_i) dwi

1. local illumination: Phong from a point light, no visibility term V, ambient for the rest;
2. Whitted: + V by shadow rays (hard shadows), mirror and refraction only;
3. direct lighting: the integral over the area light, one bounce (soft shadows);
4. path tracing: the whole integral, every bounce (colour bleeding);
5. radiosity: the diffuse part of the integral over patches (colour bleeding, no gloss).

Rungs 1-2 know only point lights, so the scene's emitters stand in as one point light at their
centroid, nudged off the surface into the scene, with the emitters' colour and the intensity
that gives Whitted's direct term (no ambient) the median of rung 3's image; the ambient light
takes the emitters' colour too.  One display for all
rungs, so that brightness and colour compare across the picture: white-balanced to the
emitters' colour (as a camera would be), exposed on the path-traced rung.

    python -m shadowvol.cli.ladder scenes/cornell.toml -o docs/ladder.png
"""

from __future__ import annotations

import time

import numpy as np

from raytrace import pathtrace, radiosity, whitted
from raytrace.backends import make_backend
from raytrace.camera import primary_rays
from raytrace.direct import emitter_points
from raytrace.intersect import dot
from shadowvol.course.layout import labelled, titled
from shadowvol.io import encode_srgb
from shadowvol.pictures import column, row
from shadowvol.scene import PointLight, Scene

# The exposure maps this percentile of the path-traced rung's radiance to EXPOSURE_WHITE.
EXPOSURE_PERCENTILE = 97.0
EXPOSURE_WHITE = 0.85
NUDGE_RELATIVE = 0.01  # the stand-in point light sits this far (x scene extent) off the emitter

CAPTIONS = [
    ("1 local", "Phong + ambient; drops V, bounces"),
    ("2 Whitted", "keeps V (point): hard shadows"),
    ("3 direct light", "area light, 1 bounce: soft shadows"),
    ("4 path traced", "all bounces: colour bleeding"),
    ("5 radiosity", "diffuse bounces: colour bleeding"),
]


def point_light_stand_in(scene: Scene) -> PointLight:
    """One point light for the emissive surfaces (see the module docstring)."""
    y, area, n_y, radiance = emitter_points(scene, 2)
    centre = (area[:, None] * y).sum(axis=0) / area.sum()
    normal = (area[:, None] * n_y).sum(axis=0)
    normal /= np.linalg.norm(normal)
    vertices, faces, _ = scene.triangles()
    tracer = make_backend("embree", vertices, faces)
    nudge = NUDGE_RELATIVE * scene.extent
    # into the scene: the side whose ray hits something nearer
    best = None
    for side in (normal, -normal):
        hit = tracer.closest_hit(centre[None] + nudge * side, side[None])
        if hit.tri[0] >= 0 and (best is None or hit.t[0] < best[0]):
            best = (float(hit.t[0]), side, int(hit.tri[0]))
    if best is None:
        raise ValueError("the emitters face nothing: no stand-in point light")
    t, side, tri = best
    below = centre + (nudge + t) * side
    n = tracer.normals[tri]
    to_y = y - below
    r2 = dot(to_y, to_y)
    cos_x = np.abs(dot(to_y, n)) / np.sqrt(r2)
    cos_y = np.abs(dot(to_y, n_y)) / np.sqrt(r2)
    irradiance = ((cos_x * cos_y * area / r2)[:, None] * radiance).sum(axis=0)
    # Whitted: kd · radiance · n·l  =  path tracing: kd / pi · irradiance   (n·l = 1 below)
    colour = irradiance / np.pi
    peak = float(colour.max())
    return PointLight(position=centre + nudge * side, color=colour / peak, intensity=peak)


def emitter_colour(scene: Scene) -> np.ndarray:
    """(3,) the emitters' power-weighted colour, mean 1 (for white balance)."""
    _, area, _, radiance = emitter_points(scene, 0)
    c = (area[:, None] * radiance).sum(axis=0)
    return c / c.mean()


def local_image(scene: Scene) -> np.ndarray:
    """Rung 1: ambient + Phong from every light, no shadow rays.  (H, W, 3) float64."""
    world = whitted.World(scene, "embree")
    o, d = primary_rays(scene.camera, scene.width, scene.height)
    t, obj, geo_n = world.nearest(o, d)
    image = np.tile(scene.background, (len(o), 1)).astype(np.float64)
    h = np.flatnonzero(obj >= 0)
    p, _, n = whitted.surface_frame(o[h], d[h], t[h], geo_n[h])
    ob = obj[h]
    colour = world.ka[ob] * scene.ambient
    for light in scene.lights:
        l = light.position - p
        l /= np.linalg.norm(l, axis=1)[:, None]
        n_dot_l = np.maximum(dot(n, l), 0.0)
        r = 2.0 * n_dot_l[:, None] * n - l
        spec = np.maximum(dot(r, -d[h]), 0.0) ** world.shininess[ob]
        colour += (world.kd[ob] * n_dot_l[:, None] + world.ks[ob] * spec[:, None]) \
            * light.radiance
    image[h] = colour
    return image.reshape(scene.height, scene.width, 3)


def rungs(scene: Scene, spp: int = 256, level: int = 4, rays: int = 1024, seed: int = 0
          ) -> tuple[list[np.ndarray], dict]:
    """The five linear images (H, W, 3) float64, and what each cost (seconds, spp, patches)."""
    info = {}
    t0 = time.perf_counter()
    direct = pathtrace.render(scene, spp=spp, seed=seed, max_depth=1, progress=False)
    full = pathtrace.render(scene, spp=spp, seed=seed, progress=False)
    t1 = time.perf_counter()
    light = point_light_stand_in(scene)
    dark = scene.replace(lights=[light], ambient=np.zeros(3))
    # medians, not means: the emitter itself is a few very bright pixels of rung 3 only
    gain = np.median(direct.image.mean(axis=2)) / max(
        np.median(whitted.render(dark, max_depth=0, progress=False).mean(axis=2)), 1e-300)
    stand_in = scene.replace(lights=[PointLight(position=light.position, color=light.color,
                                                intensity=light.intensity * gain)],
                             ambient=scene.ambient.mean() * emitter_colour(scene))
    images = [local_image(stand_in), whitted.render(stand_in, progress=False)]
    t2 = time.perf_counter()
    t3 = time.perf_counter()
    sol = radiosity.solve(scene, level=level, rays_per_patch=rays, seed=seed, shots=16)
    images += [direct.image, full.image, radiosity.display(scene, sol, interpolate=True)]
    t4 = time.perf_counter()
    info.update(local_and_whitted_s=t2 - t1, path_s=t1 - t0, radiosity_s=t4 - t3,
                spp=spp, path_mrays_per_s=(direct.rays + full.rays) / (t1 - t0) / 1e6,
                radiosity=radiosity.summary(sol), white_balance=emitter_colour(scene).tolist())
    return images, info


def picture(images: list[np.ndarray], balance: np.ndarray, scene_name: str = "") -> np.ndarray:
    """The rungs side by side, one display (white balance `balance` (3,), one exposure), each
    with its two-line caption: (h, w, 3) uint8."""

    lum = (images[3] / balance).mean(axis=2)
    white = np.percentile(lum, EXPOSURE_PERCENTILE)
    scale = EXPOSURE_WHITE / max(float(white), 1e-300) / balance
    panels = []
    for image, (name, term) in zip(images, CAPTIONS):
        panel = encode_srgb(image * scale)
        panels.append(labelled(labelled(panel, term, small=True), name, small=False))
    title = "The rendering equation, rung by rung" + (f": {scene_name}" if scene_name else "")
    return titled(column([row(panels)]), title, small=False)
