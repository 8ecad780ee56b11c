"""Teaching views: the shadow polygons over the scene, and the stencil count as a heat map.

- `draw_volume_overlay` draws, over a rendered frame, exactly the shadow-volume polygons the
  stencil pass drew for each light, translucent and outlined, coloured by role: side quads,
  near caps, far caps (caps only for casters counted with z-fail).  Depth-tested against the
  scene (nearer or equal, so caps lying on a surface and far caps at infinity over the
  background show)
  with depth clamp, so far caps at infinity are not clipped away.
- `heat_map` turns one light's signed stencil counts into a picture: the count of shadow
  volumes around each visible point, 0 where the point is lit.
"""

from __future__ import annotations

import moderngl
import numpy as np

from . import stencil
from .camera import NEARER, NEARER_OR_EQUAL
from .passes import set_uniform

ROLE_COLOURS = {  # linear RGB
    "side": (1.0, 0.62, 0.05),
    "near cap": (0.1, 0.8, 0.25),
    "far cap": (0.5, 0.25, 1.0),
}
FILL_ALPHA = 0.22
LINE_ALPHA = 0.85

# stencil count -> sRGB colour: 0 keeps the (darkened) image, 1.. warm colours, negatives blue
HEAT_PALETTE = np.array([[255, 230, 120], [255, 170, 40], [240, 90, 20], [200, 30, 40],
                         [140, 10, 90], [80, 0, 120]], np.uint8)
NEGATIVE_COLOUR = np.array([60, 140, 255], np.uint8)


def draw_volume_overlay(ctx: moderngl.Context, gl: stencil.RawGL, target, volumes,
                        light4: np.ndarray, zfail: np.ndarray) -> None:
    """Draw one light's volume polygons (prepared in `volumes` for `light4`) over `target`'s
    colour, leaving its alpha (coverage) and the lit attachment alone."""
    for p in volumes.programs:
        set_uniform(p, "u_light", tuple(float(x) for x in light4))
    target.fbo.depth_mask = False
    target.fbo.color_mask = [(True, True, True, False), (False,) * 4]
    target.fbo.use()
    ctx.enable_only(moderngl.DEPTH_TEST | moderngl.BLEND)
    ctx.depth_func = NEARER_OR_EQUAL
    ctx.blend_func = moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA
    all_objects = list(range(len(zfail)))
    capped = [int(i) for i in np.flatnonzero(zfail)]
    draws = [("side", lambda: volumes.draw_sides(all_objects))]
    if capped:
        draws += [("near cap", lambda: volumes.draw_caps(capped, near=True)),
                  ("far cap", lambda: volumes.draw_caps(capped, near=False))]
    with stencil.depth_clamped(gl):
        for wireframe, alpha in ((False, FILL_ALPHA), (True, LINE_ALPHA)):
            ctx.wireframe = wireframe
            for role, draw in draws:
                for p in volumes.programs:
                    set_uniform(p, "u_colour", (*ROLE_COLOURS[role], alpha))
                draw()
    ctx.wireframe = False
    ctx.enable_only(moderngl.DEPTH_TEST)
    ctx.depth_func = NEARER
    target.use()


def heat_map(counts: np.ndarray, image: np.ndarray | None = None) -> np.ndarray:
    """(H, W) int16 signed stencil counts -> (H, W, 3) uint8 sRGB.

    Count 0 shows the image (sRGB uint8, darkened) or black; count k >= 1 the k-th palette
    colour (the last one for all higher counts); a negative count (possible only with
    z-pass when the eye is inside a volume) is blue.
    """
    h, w = counts.shape
    out = np.zeros((h, w, 3), np.uint8) if image is None else (image // 2).astype(np.uint8)
    pos = counts > 0
    out[pos] = HEAT_PALETTE[np.minimum(counts[pos], len(HEAT_PALETTE)) - 1]
    out[counts < 0] = NEGATIVE_COLOUR
    return out


def heat_maps(stencil_counts: np.ndarray, image: np.ndarray | None = None,
              legend: bool = False) -> np.ndarray:
    """(L, H, W) counts -> one panel per light side by side, (H, L*W + gaps, 3) uint8, with a
    legend strip of LEGEND_HEIGHT rows below when `legend`."""
    if len(stencil_counts) == 0:  # no lights: nothing counted
        out = heat_map(np.zeros(stencil_counts.shape[1:], np.int16), image)
    else:
        panels = [heat_map(c, image) for c in stencil_counts]
        gap = np.full((stencil_counts.shape[1], 4, 3), 255, np.uint8)
        parts = panels[:1]
        for p in panels[1:]:
            parts += [gap, p]
        out = np.concatenate(parts, axis=1)
    return np.concatenate([out, heat_legend(out.shape[1])]) if legend else out


LEGEND_HEIGHT = 20


def heat_legend(width: int) -> np.ndarray:
    """(LEGEND_HEIGHT, width, 3) uint8: a swatch per count with its number (PIL's built-in
    bitmap font)."""
    from PIL import Image, ImageDraw

    strip = Image.new("RGB", (width, LEGEND_HEIGHT), (255, 255, 255))
    draw = ImageDraw.Draw(strip)
    entries = [("0 lit", (128, 128, 128))]
    entries += [(str(k + 1) + ("+" if k == len(HEAT_PALETTE) - 1 else ""), tuple(map(int, c)))
                for k, c in enumerate(HEAT_PALETTE)]
    entries.append(("<0", tuple(map(int, NEGATIVE_COLOUR))))
    x = 4
    for label, colour in entries:
        draw.rectangle([x, 4, x + 11, 15], fill=colour, outline=(0, 0, 0))
        draw.text((x + 15, 5), label, fill=(0, 0, 0))
        x += 22 + 6 * len(label)
    return np.asarray(strip, np.uint8)
