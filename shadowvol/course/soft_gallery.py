"""The course's soft-shadow slides (Schatten und Halbschatten), for `shadowvol.course.gallery`.

* `umbra_penumbra`: the ball of scenes/soft.toml under a point light, then under square area
  lights of growing side: a hard shadow, then an umbra (no sample reaches the floor) inside a
  penumbra (some do), both tinted and counted.
* `hard_sum`: the four hard shadows an area light of N = 4 samples is made of, and their sum,
  the soft shadow.

Umbra is "facing & no sample reaches", with the raster's facing from `Renderer.facing` (the
frame without the volume passes).  Images are supersampled; the tints come from the masks at one
sample per pixel.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from shadowvol.course import slides
from shadowvol.course.picture import Picture
from shadowvol.pictures import tint
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import AreaLight, PointLight

UMBRA_TINT = np.array([40, 60, 220], np.uint8)     # blue
PENUMBRA_TINT = np.array([255, 150, 0], np.uint8)  # orange
TINT_WEIGHT = 0.45
LIGHT_SIDES = (0.5, 1.2, 2.4)  # the area lights' side lengths, growing
LIGHT_SAMPLES = 64


def _ball_scene(g):
    """scenes/soft.toml with the ball alone over the floor (its rect light's centre kept)."""
    scene = g.scene("soft")
    keep = tuple(o for o in scene.objects if o.name in ("floor", "ball"))
    return scene.replace(objects=keep)


def _rect(centre, side: float, samples: int) -> AreaLight:
    return AreaLight("rect", centre, normal=[0.0, -1.0, 0.0], size=[side, side],
                     samples=samples, seed=1, intensity=1.3)


def _image(g, scene, w, h, lights) -> np.ndarray:
    """(h, w, 3) uint8: the supersampled frame of `scene` lit by `lights`, lights marked."""
    def frame(s):
        with Renderer(s, g.ctx) as r:
            return r.render(lights=lights).image
    image = slides.supersampled(frame, scene, w, h, g.layout.supersample)
    return slides.mark_lights(image, slides.fit(scene, w, h), g.layout, lights=lights)


def umbra_penumbra(g) -> Picture:
    L = g.layout
    scene = _ball_scene(g)
    centre = scene.lights[0].center
    lights = [PointLight(centre, intensity=1.3)] + [_rect(centre, s, LIGHT_SAMPLES)
                                                     for s in LIGHT_SIDES]
    w, h = L.cell(2, 2, legend=True)
    s = slides.fit(scene, w, h)
    cells, numbers = [], {}
    with Renderer(s, g.ctx) as r:
        for light in lights:
            frame = r.render(lights=(light,))
            facing = r.facing(lights=(light,))[0]
            umbra = facing & (frame.lit_count[0] == 0)
            penumbra = frame.penumbra[0]
            image = tint(tint(_image(g, scene, w, h, (light,)), umbra, UMBRA_TINT, TINT_WEIGHT),
                         penumbra, PENUMBRA_TINT, TINT_WEIGHT)
            name = ("point light" if isinstance(light, PointLight)
                    else f"{light.size[0]:g} x {light.size[1]:g} light, N = {light.samples}")
            cells.append((f"{name}: umbra {int(umbra.sum())} px, penumbra "
                          f"{int(penumbra.sum())} px", image))
            numbers[name] = {"umbra": int(umbra.sum()), "penumbra": int(penumbra.sum())}
    title = "Umbra and penumbra: a point light, then growing area lights"
    return Picture(
        "umbra_penumbra", title, "shadows",
        "A point light gives only hard shadows: every point sees all of the light or none.  A "
        "light with area gives an umbra, where the ball hides all of it, inside a penumbra, "
        "where the ball hides part of it; the larger the light, the wider the penumbra and the "
        "smaller the umbra, until the umbra is gone.",
        "the ball of soft.toml under a point light and under square lights of side "
        f"{', '.join(f'{s:g}' for s in LIGHT_SIDES)} ({LIGHT_SAMPLES} samples each, one dot "
        "per sample), the umbra tinted blue, the penumbra orange",
        "shadowvol demo (shadowvol.course.soft_gallery.umbra_penumbra)",
        L.compose(title, [cells[:2], cells[2:]],
                  legend=[("umbra: no sample reaches", tuple(UMBRA_TINT)),
                          ("penumbra: some samples reach", tuple(PENUMBRA_TINT)),
                          ("light (a dot per sample)", slides.SCHEME["light"])]),
        numbers=numbers)


def hard_sum(g) -> Picture:
    L = g.layout
    scene = _ball_scene(g)
    light = _rect(scene.lights[0].center, LIGHT_SIDES[1], 4)
    w, h = L.cell(3, 2, legend=False)
    s = slides.fit(scene, w, h)
    cells, hard = [], []
    with Renderer(s, g.ctx) as r:
        for k, sample in enumerate(light.hard):
            # each sample at the whole light's power, so that its hard shadow reads clearly
            alone = dataclasses.replace(sample, intensity=light.intensity)
            hard.append(r.render(lights=(alone,)).image)
            cells.append((f"sample {k + 1} of 4: a hard shadow",
                          _image(g, scene, w, h, (alone,))))
        soft = r.render(lights=(light,))
        ambient = r.render(lights=()).image
    cells.append(("their sum (each 1/4): the soft shadow", _image(g, scene, w, h, (light,))))
    title = "A soft shadow is the sum of hard ones"
    return Picture(
        "hard_sum", title, "shadows",
        "An area light is N point lights spread over it, each with 1/N of its power: every one "
        "casts a hard shadow, counted exactly in the stencil, and their sum is the soft "
        "shadow.  Where all N shadows overlap is the umbra; where only some do, the penumbra, "
        "in N - 1 steps of brightness.",
        "the four hard shadows of a 4-sample square light over the ball of soft.toml (each "
        "drawn at the whole light's power), then the frame with the light itself: the ambient "
        "term plus the mean of the four lights' terms",
        "shadowvol demo (shadowvol.course.soft_gallery.hard_sum)",
        L.compose(title, [cells[:3], cells[3:]]),
        numbers={"penumbra": int(soft.penumbra.sum()),
                 "levels": int(np.unique(soft.lit_count[0][soft.coverage]).size),
                 # the sum, in linear RGB, less the frame it shows: 0 up to float32 rounding
                 "sum_error": float(np.abs(ambient + sum(x - ambient for x in hard) / 4
                                           - soft.image).max())})
