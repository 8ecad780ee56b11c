"""The lecture's ladder as one slide: the same scene and camera through each compromise made
to solve the rendering equation

    L(x, wo) = Le(x, wo) + ∫ fr(x, wi, wo) L(x', −wi) V(x, x') cos(theta_i) dwi

1. local illumination: Phong from a point light, no visibility term V, ambient for the rest
   (it drops all coupling between surfaces);
2. Whitted: + V by shadow rays (hard shadows), mirror and refraction only (a special kind);
3. direct lighting: the integral over the area light, one bounce (soft shadows);
4. path tracing: the whole integral, every bounce (colour bleeding): Monte Carlo;
5. photon map: the whole integral too, the indirect light read from photons traced from the
   light (Monte Carlo, biased: the density estimate blurs);
6. radiosity: the diffuse part of the integral over patches (colour bleeding, no gloss: the
   other special kind).

Rungs 1-2 know only point lights, so the scene's emitters stand in as one point light at their
centroid, nudged off the surface into the scene, with the emitters' colour and the intensity
that gives Whitted's direct term (no ambient) the median of rung 3's image; the ambient light
takes the emitters' colour too.  One display for all
rungs, so that brightness and colour compare across the picture: white-balanced to the
emitters' colour (as a camera would be), exposed on the path-traced rung.

`ladder_slide` is the one picture, made by the gallery (`shadowvol demo`) and by

    python -m shadowvol.cli.ladder scenes/cornell.toml -o docs/ladder.png

alike (`FULL` at 1920x1080, `SMALL` for the gallery's `--small`).  GL-free: the slide's layout
(`shadowvol.course.slides.Layout`) is passed in.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from raytrace.backends import make_backend
from raytrace.camera import primary_rays
from raytrace.intersect import dot
from raytrace.outlook import photon, radiosity, whitted
from raytrace.outlook.direct import emitter_points
from raytrace.outlook.path import pathtrace
from shadowvol.errors import require
from shadowvol.io import encode_srgb
from shadowvol.scene import PointLight, Scene

# The exposure maps this percentile of the path-traced rung's radiance to EXPOSURE_WHITE.
EXPOSURE_PERCENTILE = 97.0
EXPOSURE_WHITE = 0.85
NUDGE_RELATIVE = 0.01  # the stand-in point light sits this far (x scene extent) off the emitter

# (name, what it keeps of the equation): the slide's two lines over each rung
RUNGS = (
    ("1 local illumination", "keeps no coupling: no V, no bounce"),
    ("2 Whitted", "keeps V to points, mirrors, glass"),
    ("3 direct light", "keeps V to the area light, 1 bounce"),
    ("4 path tracing", "keeps it all: every bounce (MC)"),
    ("5 photon map", "keeps it all, blurred by the density"),
    ("6 radiosity", "keeps the diffuse bounces only"),
)
COLUMNS = 3  # the rungs in two rows of three, read left to right


@dataclass(frozen=True)
class Settings:
    """What the rungs cost: paths per pixel (rungs 3-4), radiosity's subdivision level and
    form-factor rays per patch, photons, the photons per density estimate and the shadow rays
    per eye hit (rung 5), and
    the supersampling of the pixel-centre rungs (1, 2, 6) along each axis."""

    spp: int = 256
    level: int = 3
    rays: int = 4096
    photons: int = 1_000_000
    k: int = 200
    supersample: int = 2
    light_samples: int = 16  # rung 5's shadow rays per eye hit: its direct light unspeckled


FULL = Settings()  # the 1920x1080 slide: about two minutes on two cores
SMALL = Settings(spp=16, level=1, rays=256, photons=20_000, k=32, supersample=1,
                 light_samples=4)  # --small


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


def _box(render, scene: Scene, samples: int) -> np.ndarray:
    """`render(scene)` at `samples` x the size, box-filtered down (H, W, 3)."""
    if samples == 1:
        return render(scene)
    big = render(scene.replace(width=scene.width * samples, height=scene.height * samples))
    return big.reshape(scene.height, samples, scene.width, samples, 3).mean(axis=(1, 3))


def rungs(scene: Scene, settings: Settings = FULL, seed: int = 0
          ) -> tuple[list[np.ndarray], dict]:
    """The six linear images (H, W, 3) float64 in `RUNGS`' order, and what each cost
    (seconds, spp, photons, patches).  Rungs 5 and 6 need scipy (MissingExtra, raised before
    anything is traced)."""
    require("scipy.sparse", "the ladder's photon map and radiosity", "outlook", "scipy")
    s, info = settings, {}
    t0 = time.perf_counter()
    direct = pathtrace.render(scene, spp=s.spp, seed=seed, max_depth=1, progress=False)
    full = pathtrace.render(scene, spp=s.spp, seed=seed, progress=False)
    t1 = time.perf_counter()
    light = point_light_stand_in(scene)
    dark = scene.replace(lights=[light], ambient=np.zeros(3))
    # medians, not means: the emitter itself is a few very bright pixels of rung 3 only
    gain = np.median(direct.image.mean(axis=2)) / max(
        np.median(whitted.render(dark, max_depth=0, progress=False).mean(axis=2)), 1e-300)
    stand_in = scene.replace(lights=[PointLight(position=light.position, color=light.color,
                                                intensity=light.intensity * gain)],
                             ambient=scene.ambient.mean() * emitter_colour(scene))
    images = [_box(local_image, stand_in, s.supersample),
              _box(lambda sc: whitted.render(sc, progress=False), stand_in, s.supersample)]
    t2 = time.perf_counter()
    mapped = photon.render(scene, photons=s.photons, estimate=photon.Estimate(k=s.k),
                           spp=max(1, s.supersample ** 2), seed=seed,
                           light_samples=s.light_samples)
    t3 = time.perf_counter()
    sol = radiosity.solve(scene, level=s.level, rays_per_patch=s.rays, seed=seed, shots=16)
    images += [direct.image, full.image, mapped.image,
               _box(lambda sc: radiosity.display(sc, sol, interpolate=True), scene,
                    s.supersample)]
    t4 = time.perf_counter()
    info.update(local_and_whitted_s=t2 - t1, path_s=t1 - t0, photon_s=t3 - t2,
                radiosity_s=t4 - t3, spp=s.spp, photons=s.photons,
                path_mrays_per_s=(direct.rays + full.rays) / (t1 - t0) / 1e6,
                radiosity=radiosity.summary(sol), white_balance=emitter_colour(scene).tolist())
    return images, info


def display(images: list[np.ndarray], balance: np.ndarray) -> list[np.ndarray]:
    """The rungs as (H, W, 3) uint8 sRGB through one display: white balance `balance` (3,),
    one exposure, set on the path-traced rung."""
    lum = (images[3] / balance).mean(axis=2)
    white = np.percentile(lum, EXPOSURE_PERCENTILE)
    scale = EXPOSURE_WHITE / max(float(white), 1e-300) / balance
    return [encode_srgb(image * scale) for image in images]


def panel_size(layout) -> tuple[int, int, int]:
    """(cell width, cell height, square side) of each rung on a `layout` slide: two rows of
    `COLUMNS`, each under two label lines."""
    w, h = layout.cell(COLUMNS, 2, labels=False)
    side = max(1, min(w, h - 2 * layout.label_h))
    return w, h, side


def slide(images: list[np.ndarray], balance: np.ndarray, layout, title: str) -> np.ndarray:
    """The ladder slide ((layout.height, layout.width, 3) uint8): the rungs (square, in
    `RUNGS`' order, two rows) each under its name and what it keeps, one display."""
    w, _, side = panel_size(layout)
    cells = []
    for image, (name, keeps) in zip(display(images, balance), RUNGS):
        pad = (w - image.shape[1]) // 2
        image = np.pad(image, ((0, 0), (pad, w - image.shape[1] - pad), (0, 0)),
                       constant_values=255)
        cells.append(("", np.concatenate([layout.text(name, w), layout.text(keeps, w),
                                          image])))
    return layout.compose(title, [cells[:COLUMNS], cells[COLUMNS:]])


TITLE = "The ladder of compromises: one Cornell box, six ways to solve it"


def ladder_slide(scene: Scene, layout, settings: Settings = FULL, seed: int = 0
                 ) -> tuple[np.ndarray, dict]:
    """`scene` (square panels: its camera's field of view is kept) through every rung, as the
    slide of `layout`, and what the rungs cost (`rungs`)."""
    _, _, side = panel_size(layout)
    images, info = rungs(scene.replace(width=side, height=side), settings, seed)
    return slide(images, np.array(info["white_balance"]), layout, TITLE), info
