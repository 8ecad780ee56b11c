"""Composing uint8 pictures: panels side by side, labels, legends, heat maps, tints.

The one place pictures are put together; renderers return arrays and `shadowvol.io` writes
them.  Every array is (H, W, 3) uint8 sRGB with row 0 at the top.  matplotlib is imported only
by `figure_pixels`, which draws on the figure's own Agg canvas and never changes the process's
backend.
"""

from __future__ import annotations

import functools

import numpy as np
from PIL import Image, ImageDraw, ImageFont

WHITE = (255, 255, 255)
TITLE_BACKGROUND = (40, 40, 48)
GAP = 4  # pixels between neighbouring panels

# Fitted text strips shrink their font down to this, then cut the text short.
MIN_TEXT_SIZE = 8

# stencil count -> sRGB colour: 0 keeps the (darkened) image, 1.. warm colours, negatives blue
HEAT_PALETTE = np.array([[255, 230, 120], [255, 170, 40], [240, 90, 20], [200, 30, 40],
                         [140, 10, 90], [80, 0, 120]], np.uint8)
NEGATIVE_COLOUR = np.array([60, 140, 255], np.uint8)

# a shadow volume's faces by role, linear RGB: the `--volumes` overlay, its legend, the slides
ROLE_COLOURS = {"side": (1.0, 0.62, 0.05), "near cap": (0.1, 0.8, 0.25),
                "far cap": (0.5, 0.25, 1.0)}

ERROR_TINT = np.array([255, 0, 0], np.uint8)  # pixels a method gets wrong
ERROR_TINT_WEIGHT = 0.6


def join(images: list[np.ndarray], axis: int, gap: int = GAP,
         colour: tuple[int, int, int] = WHITE) -> np.ndarray:
    """(H, W, 3) uint8 images side by side (axis=1, equal heights) or one above another
    (axis=0, equal widths), with `gap` pixels of `colour` between neighbours."""
    shape = list(images[0].shape)
    shape[axis] = gap
    spacer = np.full(shape, colour, np.uint8)
    parts = [images[0]]
    for image in images[1:]:
        parts += [spacer, image]
    return np.concatenate(parts, axis=axis)


def row(panels: list[np.ndarray], gap: int = GAP) -> np.ndarray:
    """Panels of equal height side by side, `gap` white pixels apart."""
    return join(panels, axis=1, gap=gap)


def column(rows: list[np.ndarray], gap: int = GAP) -> np.ndarray:
    """Rows of equal width one above the other, `gap` white pixels apart."""
    return join(rows, axis=0, gap=gap)


@functools.lru_cache(maxsize=64)
def font(px: int, bold: bool = False):
    """DejaVu Sans at `px` pixels (at least MIN_TEXT_SIZE): the font matplotlib draws the 2D
    course pictures in (it ships with matplotlib), so all text looks alike and has the course's
    symbols (λ, −, ×, ∞, ·)."""
    from matplotlib import (
        font_manager,  # only to find the font file; no figure, no backend
    )

    path = font_manager.findfont(font_manager.FontProperties(
        family="DejaVu Sans", weight="bold" if bold else "normal"))
    return ImageFont.truetype(path, max(MIN_TEXT_SIZE, int(px)))


def text_strip(text: str, width: int, height: int, px: int, dark: bool = False) -> np.ndarray:
    """(height, width, 3) uint8: `text` at `px` on white (on near-black when `dark`), shrunk
    until it fits, then cut short.  The one fitted text strip of every picture."""
    strip = Image.new("RGB", (width, height), TITLE_BACKGROUND if dark else WHITE)
    draw = ImageDraw.Draw(strip)
    while px > MIN_TEXT_SIZE and draw.textlength(text, font=font(px)) > width - 12:
        px -= 1
    while len(text) > 1 and draw.textlength(text, font=font(px)) > width - 12:
        text = text[:-2] + "…"
    draw.text((8, height // 2), text, fill=WHITE if dark else (0, 0, 0), font=font(px),
              anchor="lm")
    return np.asarray(strip, np.uint8)


def blank(height: int, width: int, text: str) -> np.ndarray:
    """(height, width, 3) uint8 grey panel saying `text` in its middle."""

    panel = Image.new("RGB", (width, height), (70, 70, 70))
    ImageDraw.Draw(panel).text((6, height // 2), text, fill=(235, 235, 235),
                               font=font(caption_px(height)), anchor="lm")
    return np.asarray(panel, np.uint8)


def heat_map(counts: np.ndarray, image: np.ndarray | None = None) -> np.ndarray:
    """(H, W) signed stencil counts -> (H, W, 3) uint8 sRGB.

    Count 0 shows `image` ((H, W, 3) uint8, darkened) or black; count k >= 1 the k-th palette
    colour (the last for all higher counts); a negative count (only z-pass with the eye inside a
    volume makes one) is blue.
    """
    h, w = counts.shape
    out = np.zeros((h, w, 3), np.uint8) if image is None else (image // 2).astype(np.uint8)
    pos = counts > 0
    out[pos] = HEAT_PALETTE[np.minimum(counts[pos], len(HEAT_PALETTE)) - 1]
    out[counts < 0] = NEGATIVE_COLOUR
    return out


HEAT_LEGEND = (("0 lit", (128, 128, 128)),
               *((str(k + 1) + ("+" if k == len(HEAT_PALETTE) - 1 else ""), tuple(c))
                 for k, c in enumerate(HEAT_PALETTE)),
               ("<0", tuple(NEGATIVE_COLOUR)))


def heat_maps(counts: np.ndarray, image: np.ndarray | None = None,
              with_legend: bool = False, titles: list[str] | None = None) -> np.ndarray:
    """(L, H, W) counts -> one heat map per light side by side, each under its title when
    `titles` are given, with the legend below when asked (`captioned`)."""
    if len(counts) == 0:  # no lights: nothing counted
        panels = [heat_map(np.zeros(counts.shape[1:], np.int16), image)]
    else:
        panels = [heat_map(c, image) for c in counts]
    if titles is None and not with_legend:
        return row(panels)
    titles = titles if titles is not None else [""] * len(panels)
    return captioned(list(zip(titles, panels)), HEAT_LEGEND if with_legend else ())


def caption_px(height: int) -> int:
    """The font size of a picture's titles and legend: 1/27 of its panels' height (18 px at
    480), at least MIN_TEXT_SIZE + 3."""
    return max(MIN_TEXT_SIZE + 3, round(height / 27))


def swatch_legend(width: int, entries, px: int) -> np.ndarray:
    """(h, width, 3) uint8: a swatch and its label per (label, colour) entry in DejaVu Sans at
    `px`, left to right, on as many lines as `width` needs (h = lines x 1.6 px)."""
    f, sw, gap, line = font(px), px, px, round(1.6 * px)
    measure = ImageDraw.Draw(Image.new("RGB", (1, 1)))
    places, x, y = [], 4, 0
    for label, colour in entries:
        w = sw + px // 3 + measure.textlength(label, font=f)
        if x > 4 and x + w > width - 4:
            x, y = 4, y + line
        places.append((x, y, label, colour))
        x += w + gap
    strip = Image.new("RGB", (width, y + line), WHITE)
    draw = ImageDraw.Draw(strip)
    for x, y, label, colour in places:
        top = y + (line - sw) // 2
        draw.rectangle([x, top, x + sw, top + sw], fill=tuple(map(int, colour)),
                       outline=(0, 0, 0))
        draw.text((x + sw + px // 3, y + line // 2), label, fill=(0, 0, 0), font=f,
                  anchor="lm")
    return np.asarray(strip, np.uint8)


# Text of a picture at least this fraction of its whole height: legible when the picture is
# shown on a slide (`legible_rows`: compare's picture, raytrace masks' ground truth).
MIN_TEXT_FRACTION = 0.02


def titled_rows(rows: list[list[tuple[str, np.ndarray]]], entries, px: int) -> np.ndarray:
    """Rows of (title, (H, W, 3) uint8) panels, each panel under its title strip at `px`, short
    rows padded with white panels, one row under another, the `swatch_legend` of `entries`
    below (none when empty)."""
    per_row = max(len(r) for r in rows)
    strip_h = round(1.6 * px)
    lines = []
    for r in rows:
        h, w = r[0][1].shape[:2]
        r = r + [("", np.full((h, w, 3), 255, np.uint8))] * (per_row - len(r))
        lines.append(row([np.concatenate([text_strip(label, img.shape[1], strip_h, px), img])
                          for label, img in r]))
    out = column(lines)
    return np.concatenate([out, swatch_legend(out.shape[1], entries, px)]) if entries else out


def legible_rows(rows: list[list[tuple[str, np.ndarray]]], entries=()) -> np.ndarray:
    """`titled_rows` with the text at least `MIN_TEXT_FRACTION` of the whole picture's height
    (and `caption_px` of a panel's): a picture of several rows gets a larger font than one row
    would.  Text too long for its panel's width still shrinks to fit (`text_strip`)."""
    px = caption_px(max(img.shape[0] for r in rows for _, img in r))
    for _ in range(16):  # the strips grow with px: a few steps reach the fixed point
        out = titled_rows(rows, entries, px)
        need = int(np.ceil(MIN_TEXT_FRACTION * out.shape[0]))
        if px >= need:
            return out
        px = need
    return out


def captioned(panels: list[tuple[str, np.ndarray]], entries=(), px: int | None = None,
              title: str | None = None) -> np.ndarray:
    """Panels of equal height side by side, each under its title strip (none when every
    title is ""), the `swatch_legend` of `entries` below (none when empty) and `title` in a
    dark strip on top; text at `px` (default `caption_px` of the panels' height)."""
    px = caption_px(panels[0][1].shape[0]) if px is None else px
    strip_h = round(1.6 * px)
    if any(label for label, _ in panels):
        panels = [(label, np.concatenate([text_strip(label, img.shape[1], strip_h, px), img]))
                  for label, img in panels]
    out = row([img for _, img in panels])
    parts = [out]
    if title:
        parts.insert(0, text_strip(title, out.shape[1], strip_h, px, dark=True))
    if entries:
        parts.append(swatch_legend(out.shape[1], entries, px))
    return np.concatenate(parts)


def masks_image(lit: np.ndarray, coverage: np.ndarray) -> np.ndarray:
    """A picture of the masks, one panel per light side by side: lit white, covered but
    shadowed mid grey, not covered black."""
    panels = []
    for mask in lit:
        panel = np.zeros(mask.shape + (3,), np.uint8)
        panel[coverage] = 96
        panel[mask & coverage] = 255
        panels.append(panel)
    if not panels:
        panels = [np.where(coverage[..., None], 96, 0).astype(np.uint8).repeat(3, axis=2)]
    return join(panels, axis=1, colour=(200, 40, 40))


def tint(image: np.ndarray, where: np.ndarray, colour: np.ndarray = ERROR_TINT,
         weight: float = ERROR_TINT_WEIGHT) -> np.ndarray:
    """(H, W, 3) uint8 with the pixels of `where` (H, W) bool blended toward `colour`."""
    out = image.copy()
    out[where] = np.round((1 - weight) * image[where] + weight * colour).astype(np.uint8)
    return out


def figure_pixels(fig) -> np.ndarray:
    """(H, W, 3) uint8 of a matplotlib Figure, drawn on its own Agg canvas."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].copy()


# ---- ground truth (docs/CONVENTIONS.md, "Ground truth") ----------------------------------------

# object k's colour is OBJECT_PALETTE[(k - 1) % len]; the background is BACKGROUND
OBJECT_PALETTE = np.array([[230, 25, 75], [60, 180, 75], [255, 225, 25], [0, 130, 200],
                           [245, 130, 48], [145, 30, 180], [70, 240, 240], [240, 50, 230],
                           [210, 245, 60], [250, 190, 212], [0, 128, 128], [220, 190, 255],
                           [170, 110, 40], [255, 250, 200], [128, 0, 0], [170, 255, 195]],
                          np.uint8)
BACKGROUND = np.array([24, 24, 40], np.uint8)
UNSHADOWED = np.array([70, 70, 70], np.uint8)      # covered, no caster
LIT_COLOUR = np.array([235, 235, 235], np.uint8)
CAST_COLOUR = np.array([220, 40, 40], np.uint8)     # facing the light, something in between
ATTACHED_COLOUR = np.array([50, 90, 230], np.uint8)  # facing away from the light


def object_colours(n: int) -> np.ndarray:
    """(n, 3) uint8: the colour of objects 1..n (object k is row k - 1)."""
    return OBJECT_PALETTE[np.arange(n) % len(OBJECT_PALETTE)]


def depth_image(depth: np.ndarray) -> np.ndarray:
    """(H, W) float depth -> (H, W, 3) uint8: near white to far dark grey over the finite
    range, BACKGROUND where it is inf."""
    finite = np.isfinite(depth)
    out = np.broadcast_to(BACKGROUND, depth.shape + (3,)).copy()
    if finite.any():
        lo, hi = float(depth[finite].min()), float(depth[finite].max())
        t = (depth[finite] - lo) / max(hi - lo, 1e-30)
        out[finite] = np.round(255 - 200 * t).astype(np.uint8)[:, None]
    return out


def normal_image(normal: np.ndarray) -> np.ndarray:
    """(H, W, 3) unit normals -> (H, W, 3) uint8 as (n + 1) / 2; BACKGROUND where n = 0."""
    out = np.round((np.asarray(normal, np.float64) + 1.0) * 127.5).astype(np.uint8)
    out[~np.asarray(normal).any(axis=-1)] = BACKGROUND
    return out


def id_image(object_id: np.ndarray) -> np.ndarray:
    """(H, W) uint16 object ids -> (H, W, 3) uint8 in `object_colours`, BACKGROUND for 0."""
    ids = np.asarray(object_id, np.int64)
    table = np.concatenate([BACKGROUND[None], object_colours(max(int(ids.max()), 1))])
    return table[ids]


def shadow_kinds_image(lit: np.ndarray, facing: np.ndarray, coverage: np.ndarray) -> np.ndarray:
    """One light's (H, W) masks -> (H, W, 3) uint8: lit, cast shadow (facing & ~lit),
    attached shadow (covered & ~facing), BACKGROUND where nothing is hit."""
    out = np.broadcast_to(BACKGROUND, lit.shape + (3,)).copy()
    out[coverage & lit] = LIT_COLOUR
    out[facing & ~lit] = CAST_COLOUR
    out[coverage & ~facing] = ATTACHED_COLOUR
    return out


def casters_image(casters: np.ndarray, coverage: np.ndarray) -> np.ndarray:
    """One light's (H, W, K) uint64 casters (object j: bit j mod 64 of word j div 64; (H, W)
    for one word) -> (H, W, 3) uint8: each shadowed pixel in the mean colour of the objects
    that block it (`object_colours`), UNSHADOWED where none does, BACKGROUND where nothing is
    hit."""
    words = np.asarray(casters, np.uint64)
    words = words[..., None] if words.ndim == 2 else words
    shape = words.shape[:2]
    total = np.zeros(shape + (3,))
    count = np.zeros(shape)
    colours = object_colours(64 * words.shape[2]).astype(np.float64)
    for j in range(64 * words.shape[2]):
        on = (words[..., j // 64] >> np.uint64(j % 64)) & np.uint64(1) == 1
        if on.any():
            total[on] += colours[j]
            count[on] += 1
    out = np.broadcast_to(BACKGROUND, shape + (3,)).copy()
    out[coverage] = UNSHADOWED
    cast = count > 0
    out[cast] = np.round(total[cast] / count[cast, None]).astype(np.uint8)
    return out


def ground_truth_picture(truth, names: list[str], image: np.ndarray | None = None) -> np.ndarray:
    """The outputs of a frame side by side, each under its label: (the image,) depth, normals,
    object ids; per light lit, cast vs attached and casters; a legend of the objects' colours.

    truth : anything with `lit`, `coverage` and the ground-truth outputs as attributes (None
    for those not computed: their panels are left out); names : the objects' names;
    image : (H, W, 3) uint8 sRGB or None."""
    top = [] if image is None else [("image", image)]
    for label, key, draw in (("depth", "depth", depth_image), ("normal", "normal", normal_image),
                             ("object id", "object_id", id_image)):
        if getattr(truth, key, None) is not None:
            top.append((label, draw(getattr(truth, key))))
    rows = [top] if top else []
    for i in range(len(truth.lit)):
        panels = [(f"light {i}: lit", masks_image(truth.lit[i:i + 1], truth.coverage))]
        if getattr(truth, "facing", None) is not None:
            panels.append((f"light {i}: cast (red) / attached (blue)",
                           shadow_kinds_image(truth.lit[i], truth.facing[i], truth.coverage)))
        if getattr(truth, "casters", None) is not None:
            panels.append((f"light {i}: casters", casters_image(truth.casters[i],
                                                                truth.coverage)))
        rows.append(panels)
    entries = [(name, tuple(c)) for name, c in zip(names, object_colours(len(names)))]
    return legible_rows(rows, entries)
