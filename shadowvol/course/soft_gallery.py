"""The course's soft-shadow pictures (Schatten und Halbschatten), for `shadowvol.course.gallery`.

* `umbra_penumbra`: the ball of scenes/soft.toml under a point light, then under square area
  lights of growing side: a hard shadow, then an umbra (no sample reaches the floor) inside a
  penumbra (some do), both tinted and counted.
* `hard_sum`: four of the hard shadows an area light of N = 4 samples is made of, and their sum,
  the soft shadow.

Umbra is "facing & no sample reaches", with the raster's facing from `Renderer.facing` (the
frame without the volume passes).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from shadowvol.course.gallery import Gallery, Picture, labelled, row, tint, titled
from shadowvol.scene import AreaLight, PointLight

UMBRA_TINT = np.array([40, 60, 220], np.uint8)     # blue
PENUMBRA_TINT = np.array([255, 150, 0], np.uint8)  # orange
TINT_WEIGHT = 0.45
LIGHT_SIDES = (0.5, 1.2, 2.4)  # the area lights' side lengths, growing
LIGHT_SAMPLES = 64


def _ball_scene(g: Gallery):
    """scenes/soft.toml with the ball alone over the floor (its rect light's centre kept)."""
    scene = g.scene("soft")
    keep = tuple(o for o in scene.objects if o.name in ("floor", "ball"))
    return scene.replace(objects=keep)


def _rect(centre, side: float, samples: int) -> AreaLight:
    return AreaLight("rect", centre, normal=[0.0, -1.0, 0.0], size=[side, side],
                     samples=samples, seed=1, intensity=1.3)


def umbra_penumbra(g: Gallery) -> Picture:
    from shadowvol.io import encode_srgb
    from shadowvol.raster.renderer import Renderer

    scene = _ball_scene(g)
    centre = scene.lights[0].center
    lights = [PointLight(centre, intensity=1.3)] + [_rect(centre, s, LIGHT_SAMPLES)
                                                     for s in LIGHT_SIDES]
    panels, numbers = [], {}
    with Renderer(scene, g.ctx) as r:
        for light in lights:
            frame = r.render(lights=(light,))
            facing = r.facing(lights=(light,))[0]
            umbra = facing & (frame.lit_count[0] == 0)
            penumbra = frame.penumbra[0]
            image = tint(tint(encode_srgb(frame.image), umbra, UMBRA_TINT, TINT_WEIGHT),
                         penumbra, PENUMBRA_TINT, TINT_WEIGHT)
            name = ("point light" if isinstance(light, PointLight)
                    else f"{light.size[0]:g} x {light.size[1]:g} light, N = {light.samples}")
            label = f"{name}: umbra {int(umbra.sum())} px, penumbra {int(penumbra.sum())} px"
            panels.append(labelled(image, label, g.small))
            numbers[name] = {"umbra": int(umbra.sum()), "penumbra": int(penumbra.sum())}
    title = "Umbra (blue) and penumbra (orange): a point light, then growing area lights"
    return Picture(
        "umbra_penumbra", title,
        "A point light gives only hard shadows: every point sees all of the light or none.  A "
        "light with area gives an umbra, where the ball hides all of it, inside a penumbra, "
        "where the ball hides part of it; the larger the light, the wider the penumbra and the "
        "smaller the umbra, until the umbra is gone.",
        "the ball of soft.toml under a point light and under square lights of side "
        f"{', '.join(f'{s:g}' for s in LIGHT_SIDES)} ({LIGHT_SAMPLES} samples each), the "
        "umbra tinted blue, the penumbra orange",
        "shadowvol demo (shadowvol.course.soft_gallery.umbra_penumbra)",
        titled(row(panels), title, g.small), numbers=numbers)


def hard_sum(g: Gallery) -> Picture:
    from shadowvol.io import encode_srgb
    from shadowvol.raster.renderer import Renderer

    scene = _ball_scene(g)
    light = _rect(scene.lights[0].center, LIGHT_SIDES[1], 4)
    panels, hard = [], []
    with Renderer(scene, g.ctx) as r:
        for k, sample in enumerate(light.hard):
            # each sample at the whole light's power, so that its hard shadow reads clearly
            alone = dataclasses.replace(sample, intensity=light.intensity)
            hard.append(r.render(lights=(alone,)).image)
            panels.append(labelled(encode_srgb(hard[-1]), f"sample {k + 1} of 4: a hard shadow",
                                   g.small))
        soft = r.render(lights=(light,))
        ambient = r.render(lights=()).image
    panels.append(labelled(encode_srgb(soft.image), "their sum (each 1/4): the soft shadow",
                           g.small))
    title = "A soft shadow is the sum of hard ones"
    return Picture(
        "hard_sum", title,
        "An area light is N point lights spread over it, each with 1/N of its power: every one "
        "casts a hard shadow, counted exactly in the stencil, and their sum is the soft "
        "shadow.  Where all N shadows overlap is the umbra; where only some do, the penumbra, "
        "in N - 1 steps of brightness.",
        "the four hard shadows of a 4-sample square light over the ball of soft.toml (each "
        "drawn at the whole light's power), then the frame with the light itself: the ambient "
        "term plus the mean of the four lights' terms",
        "shadowvol demo (shadowvol.course.soft_gallery.hard_sum)",
        titled(row(panels), title, g.small),
        numbers={"penumbra": int(soft.penumbra.sum()),
                 "levels": int(np.unique(soft.lit_count[0][soft.coverage]).size),
                 # the sum, in linear RGB, less the frame it shows: 0 up to float32 rounding
                 "sum_error": float(np.abs(ambient + sum(h - ambient for h in hard) / 4
                                           - soft.image).max())})
