"""The course's soft-shadow slides (Schatten und Halbschatten), for `shadowvol.course.gallery`.

* `umbra_penumbra`: the ball of scenes/soft.toml under a point light, then under square area
  lights of growing side: a hard shadow, then an umbra (no sample reaches the floor) inside a
  penumbra (some do), both tinted and counted.
* `exact_penumbra`: the penumbra of the middle light computed (the ray tracer's exact visible
  fraction V and its noise-free image, `raytrace.outlook.analytic`) beside the rasterizer's
  sampled ones at N = 16, 64, 256, with each one's error |lit_count / N - V| mapped and its
  mean and largest over the penumbra on the slide.
* `hard_sum`: the four hard shadows an area light of N = 4 samples is made of (samples one in
  each quarter of the light, far apart, so the four shadows visibly part), their sum, the soft
  shadow, and how many of the four samples reach each point (0: the umbra).

Both are seen from higher up than soft.toml's camera (`CAMERA`), so the light, its outline and
a dot per sample are in the frame above the ball.

Umbra is "facing & no sample reaches", with the raster's facing from `Renderer.facing` (the
frame without the volume passes).  Images are supersampled; the tints come from the masks at one
sample per pixel.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from PIL import Image, ImageDraw

from shadowvol.course import slides
from shadowvol.course.picture import Picture
from shadowvol.pictures import tint
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import AreaLight, Camera, PointLight

UMBRA_TINT = np.array([40, 60, 220], np.uint8)     # blue
PENUMBRA_TINT = np.array([255, 150, 0], np.uint8)  # orange
TINT_WEIGHT = 0.45
LIGHT_SIDES = (0.5, 1.2, 2.4)  # the area lights' side lengths, growing
LIGHT_SAMPLES = 64
EXACT_SAMPLES = (16, 64, 256)  # exact_penumbra's sampled panels
ERROR_FULL = 0.1  # exact_penumbra's error maps: |lit_count / N - V| at full red
# V's rounding: the exact area of a wholly hidden light comes out ~1e-16 of the light's, not 0;
# the penumbra is where V is further than this from 0 and 1
V_ROUNDING = 1e-9
# hard_sum's light: 4 jittered samples, one per quarter; seed 32 puts each near its quarter's
# outer corner (the four at least 1.2 apart), so the four hard shadows part by about half the
# ball's width
HARD_SIDE, HARD_SEED = 2.0, 32
# the four samples' colours: each sample's marker and its shadow's outline
SAMPLE_COLOURS = ((220, 20, 60), (0, 150, 70), (150, 40, 200), (0, 120, 230))
# how many of the 4 samples reach a point: 0 (the umbra) .. 3; 4 (lit) keeps the image
REACH_COLOURS = (tuple(UMBRA_TINT), (230, 80, 0), (255, 150, 40), (255, 215, 130))
# above and in front of the ball, higher than the light: the light and its samples in view
CAMERA = Camera(eye=[-1.3, 6.6, 4.6], target=[-1.9, 2.0, -0.9], fov_y=47.0)


def _ball_scene(g):
    """scenes/soft.toml with the ball alone over the floor (its rect light's centre kept), seen
    by `CAMERA`."""
    scene = g.scene("soft")
    keep = tuple(o for o in scene.objects if o.name in ("floor", "ball"))
    return scene.replace(objects=keep, camera=CAMERA)


def _rect(centre, side: float, samples: int, seed: int = 1) -> AreaLight:
    return AreaLight("rect", centre, normal=[0.0, -1.0, 0.0], size=[side, side],
                     samples=samples, seed=seed, intensity=1.3)


def _frame(g, scene, w, h, lights) -> np.ndarray:
    """(h, w, 3) uint8: the supersampled frame of `scene` lit by `lights`."""
    def frame(s):
        with Renderer(s, g.ctx) as r:
            return r.render(lights=lights).image
    return slides.supersampled(frame, scene, w, h, g.layout.supersample)


def _image(g, scene, w, h, lights) -> np.ndarray:
    """(h, w, 3) uint8: the supersampled frame of `scene` lit by `lights`, lights marked."""
    return slides.mark_lights(_frame(g, scene, w, h, lights), slides.fit(scene, w, h),
                              g.layout, lights=lights)


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
        f"{', '.join(f'{s:g}' for s in LIGHT_SIDES)} ({LIGHT_SAMPLES} samples each; each light "
        "in view above the ball, its outline and one dot per sample), the umbra tinted blue, "
        "the penumbra orange",
        "shadowvol demo (shadowvol.course.soft_gallery.umbra_penumbra)",
        L.compose(title, [cells[:2], cells[2:]],
                  legend=[("umbra: no sample reaches", tuple(UMBRA_TINT)),
                          ("penumbra: some samples reach", tuple(PENUMBRA_TINT)),
                          ("light (a dot per sample)", slides.SCHEME["light"])]),
        numbers=numbers)


def _visibility_map(v: np.ndarray, seen: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8: the visible fraction v in grey (black 0, white 1) where `seen`, the
    background pale blue."""
    grey = np.round(255 * np.clip(v, 0, 1)).astype(np.uint8)
    out = np.repeat(grey[..., None], 3, axis=2)
    out[~seen] = (205, 215, 235)
    return out


def _error_map(error: np.ndarray, seen: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8: |error| from white (0) to red (ERROR_FULL or more) where `seen`."""
    f = np.clip(error / ERROR_FULL, 0, 1)
    out = np.stack([np.full_like(f, 255), 255 * (1 - f), 255 * (1 - f)], axis=-1)
    out = np.round(out).astype(np.uint8)
    out[~seen] = (205, 215, 235)
    return out


def _written(image: np.ndarray, L, lines: list[str]) -> np.ndarray:
    """`image` with `lines` written in its top left corner (the error maps' numbers, legible
    at every slide size)."""
    img = Image.fromarray(image)
    draw = ImageDraw.Draw(img)
    size = max(9, L.px(34))
    for k, line in enumerate(lines):
        draw.text((L.px(12), L.px(10) + k * int(1.2 * size)), line, fill=slides.SCHEME["ink"],
                  font=slides.font(size, bold=True))
    return np.asarray(img, np.uint8)


def exact_penumbra(g) -> Picture:
    """The middle light's penumbra exact and sampled (see the module).  MissingExtra without
    shapely (the exact visible region)."""
    from raytrace.exact_soft import exact_visibility
    from raytrace.groundtruth import ground_truth
    from raytrace.outlook import analytic

    L = g.layout
    scene = _ball_scene(g)
    side = LIGHT_SIDES[1]
    exact_light = _rect(scene.lights[0].center, side, EXACT_SAMPLES[-1])
    w, h = L.cell(4, 2, legend=True)
    s = slides.fit(scene.replace(lights=(exact_light,)), w, h)
    v = exact_visibility(s).visibility[0]
    seen = ground_truth(s, outputs=("object_id",)).object_id > 0
    penumbra = seen & (v > V_ROUNDING) & (v < 1 - V_ROUNDING)
    image = slides.mark_lights(slides.encode_srgb(analytic.render(s)), s, L)
    top = [("exact (computed)", image)]
    bottom = [("exact V", _written(_visibility_map(v, seen), L,
                                   [f"penumbra {int(penumbra.sum())} px"]))]
    numbers = {"penumbra": int(penumbra.sum()),
               "levels": {"exact": len(np.unique(np.round(v[penumbra] * 255)))}}
    with Renderer(s, g.ctx) as r:
        for n in EXACT_SAMPLES:
            light = _rect(scene.lights[0].center, side, n)
            frame = r.render(lights=(light,))
            error = np.abs(frame.lit_count[0] / n - v)
            mean, worst = float(error[penumbra].mean()), float(error[penumbra].max())
            numbers[f"N = {n}"] = {"mean": mean, "max": worst}
            numbers["levels"][f"N = {n}"] = len(np.unique(frame.lit_count[0][penumbra]))
            top.append((f"N = {n} samples", _image(g, scene, w, h, (light,))))
            bottom.append((f"N = {n}: |error|",
                           _written(_error_map(error, seen), L,
                                    [f"mean {mean:.3f}", f"max {worst:.3f}"])))
    title = "Umbra and penumbra, exact and sampled"
    return Picture(
        "exact_penumbra", title, "shadows",
        "The visible part of a polygonal light seen from a point can be computed: the light "
        "less the union of the occluders' shadows on it (back-projection).  Its area over the "
        "light's is the exact visible fraction V, the limit of the sampled count lit_count / N; "
        "the samples' staircase of N levels approaches it, their error falling with N.",
        f"the ball of soft.toml under the {side:g} x {side:g} light: its exact image (the ray "
        "tracer's noise-free direct light) and V, then the rasterizer's frames with 16, 64 and "
        "256 stratified samples, each with its error |lit_count / N - V| (white 0, red "
        f"{ERROR_FULL:g} or more), the mean and largest over the penumbra in its label",
        "shadowvol demo (shadowvol.course.soft_gallery.exact_penumbra)",
        L.compose(title, [top, bottom],
                  legend=[("V = 0: the umbra", (0, 0, 0)),
                          ("0 < V < 1: the penumbra", (128, 128, 128)),
                          (f"error {ERROR_FULL:g} or more", (255, 0, 0)),
                          ("light (a dot per sample)", slides.SCHEME["light"])]),
        numbers=numbers)


def outline(mask: np.ndarray, width: int) -> np.ndarray:
    """(H, W) bool: the pixels of `mask` within `width` pixels (chessboard distance) of a
    pixel outside it: its border, drawn inward."""
    inside = mask.copy()
    for _ in range(width):
        pad = np.pad(inside, 1)
        inside = (inside & pad[:-2, 1:-1] & pad[2:, 1:-1] & pad[1:-1, :-2] & pad[1:-1, 2:]
                  & pad[:-2, :-2] & pad[:-2, 2:] & pad[2:, :-2] & pad[2:, 2:])
    return mask & ~inside


def _draw_samples(image, s, L, light, current=None) -> np.ndarray:
    """`image` with the light's outline and its samples numbered 1..N in SAMPLE_COLOURS: the
    `current` one (an index) large, the others small; all large when `current` is None."""
    img = Image.fromarray(image)
    draw = ImageDraw.Draw(img)
    edge = slides.area_outline(light)
    xy, _ = slides.project(s, np.c_[np.concatenate([edge, light.positions]),
                                    np.ones(len(edge) + light.samples)])
    ink = slides.SCHEME["ink"]
    draw.polygon([tuple(p) for p in xy[:len(edge)]], fill=(255, 246, 200), outline=ink,
                 width=L.px(3))
    for k, (x, y) in enumerate(xy[len(edge):]):
        big = current is None or k == current
        r = L.px(22 if big else 12)
        draw.ellipse([x - r, y - r, x + r, y + r], fill=SAMPLE_COLOURS[k] if big else
                     (255, 255, 255), outline=SAMPLE_COLOURS[k], width=L.px(4))
        draw.text((x, y), str(k + 1), fill=(255, 255, 255) if big else SAMPLE_COLOURS[k],
                  font=slides.font(L.px(30 if big else 18), bold=True), anchor="mm")
    return np.asarray(img, np.uint8)


def _outlined(image, shadows, which, width) -> np.ndarray:
    """`image` with the outlines of `shadows[k]` for k in `which`, in SAMPLE_COLOURS."""
    out = image.copy()
    for k in which:
        out[outline(shadows[k], width)] = SAMPLE_COLOURS[k]
    return out


def _reach_map(image, lit_count, facing) -> np.ndarray:
    """`image` paled, with the points some sample faces but not all four reach coloured by
    how many do (REACH_COLOURS)."""
    out = (128 + image // 2).astype(np.uint8)
    for k, colour in enumerate(REACH_COLOURS):
        out[facing & (lit_count == k)] = colour
    return out


def hard_sum(g) -> Picture:
    L = g.layout
    scene = _ball_scene(g)
    light = _rect(scene.lights[0].center, HARD_SIDE, 4, HARD_SEED)
    w, h = L.cell(3, 2, legend=True)
    s = slides.fit(scene, w, h)
    cells, hard, shadows = [], [], []
    with Renderer(s, g.ctx) as r:
        for k, sample in enumerate(light.hard):
            # each sample at the whole light's power, so that its hard shadow reads clearly
            alone = dataclasses.replace(sample, intensity=light.intensity)
            frame = r.render(lights=(alone,))
            hard.append(frame.image)
            shadows.append(r.facing(lights=(alone,))[0] & ~frame.lit[0])  # cast, not attached
            image = _outlined(_frame(g, scene, w, h, (alone,)), shadows, [k], L.px(3))
            cells.append((f"sample {k + 1} alone: its hard shadow",
                          _draw_samples(image, s, L, light, current=k)))
        soft = r.render(lights=(light,))
        facing = r.facing(lights=(light,))[0]
        ambient = r.render(lights=()).image
    image = _outlined(_frame(g, scene, w, h, (light,)), shadows, range(4), L.px(3))
    cells.append(("all four, each 1/4: the soft shadow", _draw_samples(image, s, L, light)))
    count = soft.lit_count[0]
    cells.append(("how many of the 4 samples reach",
                  _draw_samples(_reach_map(image, count, facing), s, L, light)))
    apart = [int((a ^ b).sum()) for i, a in enumerate(shadows) for b in shadows[i + 1:]]
    title = "A soft shadow is the sum of hard ones"
    return Picture(
        "hard_sum", title, "shadows",
        "An area light is N point lights spread over it, each with 1/N of its power: every one "
        "casts a hard shadow, counted exactly in the stencil, and their sum is the soft "
        "shadow.  Where all N shadows overlap is the umbra; where only some do, the penumbra, "
        "in N - 1 steps of brightness.",
        f"the four hard shadows of a 4-sample {HARD_SIDE:g} x {HARD_SIDE:g} light over the ball "
        "of soft.toml (each drawn at the whole light's power, its sample and its shadow's "
        "outline in its own colour), the frame with the light itself (the ambient term plus "
        "the mean of the four lights' terms, the four outlines over it), and how many of the "
        "four samples reach each point",
        "shadowvol demo (shadowvol.course.soft_gallery.hard_sum)",
        L.compose(title, [cells[:3], cells[3:]],
                  legend=[(label, c) for label, c in zip(
                      ("0 of 4 samples reach: umbra", "1 of 4", "2 of 4",
                       "3 of 4 (1 to 3: penumbra)"), REACH_COLOURS)] +
                         [("4 of 4: lit", (255, 255, 255))]),
        numbers={"penumbra": int(soft.penumbra.sum()),
                 "levels": int(np.unique(count[soft.coverage]).size),
                 "shadow_px": [int(m.sum()) for m in shadows], "apart_px": apart,
                 "umbra": int((facing & (count == 0)).sum()),
                 # the sum, in linear RGB, less the frame it shows: 0 up to float32 rounding
                 "sum_error": float(np.abs(ambient + sum(x - ambient for x in hard) / 4
                                           - soft.image).max())})
