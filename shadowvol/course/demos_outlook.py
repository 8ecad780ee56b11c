"""The gallery's last chapter: global illumination, the rendering equation and its solutions
(Kajiya 1986), in the lecture's order: the equation with its terms named, the ladder of
compromises on one Cornell box (`shadowvol.course.ladder`), path tracing against the photon
map on a caustic, and distributed ray tracing (aliasing, glossy reflection, depth of field).
Each demo takes the `Gallery` and returns a `Picture` (see `gallery`).  The ladder and the
caustic need scipy (the `outlook` extra): without it they raise MissingExtra, and the gallery
leaves them out.

`--small` (CI) renders with few samples and photons; the 1920x1080 slides take about two and a
half minutes together on two cores (docs/course.md).
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from raytrace.outlook import photon, whitted
from raytrace.outlook.path import pathtrace
import shadowvol.course.ladder
from shadowvol.course import slides
from shadowvol.course.demos_tracing import ZOOM_FRACTION, crop_window, zoom
from shadowvol.course.equation_picture import equation_figure
from shadowvol.course.picture import Picture
from shadowvol.io import encode_srgb
from shadowvol.pictures import figure_pixels

SECTION = "gi"
ALIASING_SPP = 16                       # "the same edge at 1 and 16 samples"
CAUSTIC = {"full": dict(spp=64, photons=500_000, k=50, eye=4),
           "small": dict(spp=8, photons=50_000, k=30, eye=1)}
GLOSS = (0.08, 0.3)                     # the mirror balls' roughness, two panels
APERTURE = 0.12                         # the lens radius (scene units) of the depth of field
DISTRIBUTED_SPP = {"full": 16, "small": 4}
GLOSS_ZOOM = 0.85                       # the field of view narrowed: the balls fill the panels


def _size_flags(g) -> str:
    return " --small" if g.small else ("" if g.size == slides.SLIDE else
                                       f" --size {g.size[0]}x{g.size[1]}")


def rendering_equation(g) -> Picture:
    L = g.layout
    w, h = L.cell(1, 1, labels=False)
    image = figure_pixels(equation_figure(w, h, text_px=L.px(slides.LABEL_PX)))
    title = "The rendering equation (Kajiya 1986)"
    return Picture(
        "rendering_equation", title, SECTION,
        "Everything the course rendered is an approximation of one equation: the radiance "
        "leaving a point toward the eye is what it emits plus the integral, over the "
        "hemisphere of directions above it, of the BRDF times the incoming radiance times "
        "the cosine of its angle to the normal.  The incoming radiance is what leaves the "
        "nearest surface in that direction, so the unknown L appears on both sides: every "
        "surface lights every other one.",
        "the equation, each term coloured and named (emitted, the integral over the "
        "hemisphere, the BRDF, the incoming radiance, the cosine); what it says; the "
        "hemisphere at x with the normal, an incoming and an outgoing direction, the angle "
        "and a BRDF lobe",
        "shadowvol demo (shadowvol.course.demos_outlook.rendering_equation)",
        L.compose(title, [[("", image)]]))


def ladder(g) -> Picture:
    L = g.layout
    settings = shadowvol.course.ladder.SMALL if g.small else shadowvol.course.ladder.FULL
    image, info = shadowvol.course.ladder.ladder_slide(g.scene("cornell"), L, settings)
    times = {k: round(v, 1) for k, v in info.items() if k.endswith("_s")}
    return Picture(
        "ladder", shadowvol.course.ladder.TITLE, SECTION,
        "The lecture's ladder of compromises, on one Cornell box and one display: local "
        "illumination drops all coupling between surfaces (no shadows, no bounces); Whitted "
        "keeps visibility to point lights and the special kind of coupling through mirrors "
        "and glass; direct lighting keeps the area light's visibility (soft shadows) but one "
        "bounce; Monte Carlo solves it all: path tracing with noise, the photon map with the "
        "blur of its density estimate; radiosity keeps the other special kind, diffuse "
        "bounces only, noise-free but with no gloss.  Colour bleeds from the red and green walls "
        f"only on the global rungs 4-6.  Path tracing {info['spp']} paths per pixel "
        f"({times['path_s']} s for rungs 3-4), photon map {info['photons']:,} photons "
        f"({times['photon_s']} s), radiosity {info['radiosity']}.",
        "scenes/cornell.toml six times: local Phong + ambient from a point light standing in "
        "for the ceiling's light, Whitted with it, direct light from the emitter (one "
        "bounce), path traced, photon mapped, radiosity (interpolated); each rung named with "
        "what it keeps of the equation",
        f"python -m shadowvol.cli.ladder {g.path('cornell')} -o ladder.png{_size_flags(g)}",
        image, numbers={**info, "rungs": [name for name, _ in shadowvol.course.ladder.RUNGS]})


def caustic(g) -> Picture:
    L = g.layout
    c = CAUSTIC["small" if g.small else "full"]
    scene = g.scene("caustic")
    w, h = L.cell(2, 1)
    s = slides.fit(scene, w, h, cover=True)
    t0 = time.perf_counter()
    mapped = photon.render(s, photons=c["photons"], estimate=photon.Estimate(k=c["k"]),
                           spp=c["eye"])   # first: a missing scipy stops it before tracing
    t1 = time.perf_counter()
    path = pathtrace.render(s, spp=c["spp"], progress=False)
    t2 = time.perf_counter()
    caustic_photons = len(mapped.maps.caustic)
    # one exposure for both: the path tracer's floor, away from the caustic, as mid-grey
    scale = 0.18 / max(float(np.median(path.image.mean(axis=2))), 1e-300)
    title = "A caustic: path tracing finds it by chance, photons carry it"
    return Picture(
        "caustic", title, SECTION,
        "A glass ball focuses a small light onto the floor (scenes/caustic.toml).  The path "
        "tracer's shadow rays cannot see the light through the glass, so its light reaches "
        "the caustic only when a path from the eye, refracted twice, happens to hit the small "
        f"emitter: with {c['spp']} paths per pixel ({t2 - t1:.1f} s) the caustic is a cloud "
        "of fireflies.  The photon map traces photons from the light through the glass and "
        f"stores where they land ({caustic_photons:,} of {c['photons']:,} in the caustic "
        f"map): the caustic is read from their density, smooth, in {t1 - t0:.1f} s.",
        "the caustic scene path traced and photon mapped (the caustic map's k = "
        f"{c['k']} nearest photons per estimate, {c['eye']} eye rays per pixel), one exposure",
        f"raytrace render {g.path('caustic')} --integrator photon --photons {c['photons']} "
        f"--knn {c['k']} -o caustic.png (and --integrator path --spp {c['spp']})",
        L.compose(title, [[(f"path tracing, {c['spp']} paths per pixel: fireflies",
                            encode_srgb(path.image * scale)),
                           (f"photon map, {c['photons']:,} photons: the caustic map",
                            encode_srgb(mapped.image * scale))]]),
        numbers={"caustic_photons": caustic_photons, "path_s": t2 - t1,
                 "photon_s": t1 - t0})


def _framed(image: np.ndarray, x: int, y: int, cw: int, ch: int, px: int) -> np.ndarray:
    out = image.copy()
    colour = slides.SCHEME["eye"]
    for rows, cols in ((slice(y, y + px), slice(x, x + cw)),
                       (slice(y + ch - px, y + ch), slice(x, x + cw)),
                       (slice(y, y + ch), slice(x, x + px)),
                       (slice(y, y + ch), slice(x + cw - px, x + cw))):
        out[rows, cols] = colour
    return out


def aliasing(g) -> Picture:
    L = g.layout
    scene = g.scene("cage")
    w, h = L.cell(2, 2)
    s = slides.fit(scene, w, h)
    one, many = (encode_srgb(i) for i in whitted.aliasing_pair(s, spp=ALIASING_SPP,
                                                                progress=False))
    differs = np.abs(one.astype(int) - many.astype(int)).sum(axis=2) > 24
    cw, ch = max(2, w // ZOOM_FRACTION), max(2, h // ZOOM_FRACTION)
    x, y = crop_window(differs, cw, ch)
    px = max(1, L.px(4))
    title = f"Aliasing: the same edges at 1 and {ALIASING_SPP} samples per pixel"
    return Picture(
        "aliasing", title, SECTION,
        "An image samples the scene at discrete points: one ray through each pixel's centre "
        "sees an edge as all or nothing, so edges become staircases and the thin bars of the "
        "cage break up (aliasing).  Distributed ray tracing (Cook, Porter, Carpenter 1984) "
        f"traces {ALIASING_SPP} stratified rays per pixel and averages them: each edge pixel "
        "gets the share of it the edge covers, for geometry and shadow edges alike.",
        f"the cage ray traced at one sample per pixel and at {ALIASING_SPP} (box filter); "
        f"below, the boxed part of each enlarged x{ZOOM_FRACTION}, one square per pixel",
        f"raytrace render {g.path('cage')} --spp {ALIASING_SPP} -o aliasing.png "
        "(raytrace.outlook.whitted.aliasing_pair)",
        L.compose(title, [[("1 sample per pixel (the centre)", _framed(one, x, y, cw, ch, px)),
                           (f"{ALIASING_SPP} samples per pixel",
                            _framed(many, x, y, cw, ch, px))],
                          [(f"1 sample, zoom x{ZOOM_FRACTION}: a staircase",
                            zoom(one, x, y, cw, ch, w, h)),
                           (f"{ALIASING_SPP} samples, zoom x{ZOOM_FRACTION}: the coverage",
                            zoom(many, x, y, cw, ch, w, h))]]),
        numbers={"pixels_differ": int(differs.sum())})


def _rough(scene, roughness: float):
    """`scene` with its mirrors (reflectivity > 0.5) given `roughness`."""
    objects = tuple(replace(o, material=replace(o.material, roughness=roughness))
                    if o.material.reflectivity > 0.5 else o for o in scene.objects)
    return scene.replace(objects=objects)


def _focused(scene, name: str, aperture: float):
    """`scene` through a lens of radius `aperture`, focused on object `name`'s centre."""
    cam = scene.camera
    centre = next(o for o in scene.objects if o.name == name).analytic.center
    view = (cam.target - cam.eye) / np.linalg.norm(cam.target - cam.eye)
    depth = float(np.dot(centre - cam.eye, view))
    return scene.replace(camera=replace(cam, aperture=aperture, focus_distance=depth))


def glossy_dof(g) -> Picture:
    L = g.layout
    spp = DISTRIBUTED_SPP["small" if g.small else "full"]
    scene = g.scene("whitted_best")
    scene = scene.replace(camera=replace(scene.camera, fov_y=scene.camera.fov_y * GLOSS_ZOOM))
    w, h = L.cell(2, 2)
    s = slides.fit(scene, w, h)
    draw = lambda sc, n: encode_srgb(whitted.render(sc, spp=n, progress=False))
    sharp = slides.supersampled(lambda sc: whitted.render(sc, progress=False), scene, w, h,
                                L.supersample)
    cells = [("mirror: roughness 0, the classic image", sharp)]
    cells += [(f"glossy: roughness {r:g}, {spp} samples per pixel", draw(_rough(s, r), spp))
              for r in GLOSS]
    cells.append((f"depth of field: lens radius {APERTURE:g}, focus on the glass ball",
                  draw(_focused(s, "glass ball", APERTURE), spp)))
    title = "Distributed ray tracing: glossy reflection and depth of field"
    return Picture(
        "glossy_dof", title, SECTION,
        "Distributed ray tracing spreads each pixel's samples over the other dimensions of "
        "the integral too: each sample reflects in its own direction drawn from a Phong lobe "
        "about the mirror direction (glossy: the rougher, the blurrier the reflections of "
        "reflections), or starts from its own point on a lens focused at one depth (depth of "
        "field: the glass ball sharp, nearer and farther things blurred).  Averaged over the "
        "pixel, the blur is the integral; with few samples it is noise.",
        f"whitted_best ray traced: the mirror balls sharp (supersampled), glossy at "
        f"roughness {' and '.join(f'{r:g}' for r in GLOSS)}, and the mirrors sharp through "
        f"a thin lens of radius {APERTURE:g} focused on the glass ball ({spp} samples per "
        "pixel each)",
        f"raytrace render {g.path('whitted_best')} --spp {spp} -o glossy.png (with "
        "roughness in the mirror material, aperture and focus_distance in [camera])",
        L.compose(title, [cells[:2], cells[2:]]), numbers={"spp": spp})


DEMOS = (rendering_equation, ladder, caustic, aliasing, glossy_dof)
