"""Slides: the gallery's layout at projector size, its one colour scheme, supersampling and the
light marker.

Every gallery picture is exactly one slide, `Layout.width` x `Layout.height` (default 1920x1080,
16:9): a dark title strip, a grid of labelled panels, and an optional legend strip.  Text sizes
scale with the slide's height and are at least LABEL_PX (labels, legends) and TITLE_PX (titles)
at 1080p, legible from the back of a lecture hall.

Images are supersampled (SUPERSAMPLE^2 pixel-centre samples, box-filtered in linear light);
masks, and every count a picture reports, stay one sample per pixel (CONVENTIONS.md).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from PIL import Image, ImageDraw

from shadowvol import pictures
from shadowvol.io import encode_srgb
from shadowvol.planes import default_plane_axes
from shadowvol.pictures import ROLE_COLOURS, font, text_strip  # noqa: F401 - the slides' text
from shadowvol.raster.projection import view_projection

SLIDE = (1920, 1080)
SMALL_SLIDE = (480, 270)     # --small: a quarter of the width and height (CI)
SUPERSAMPLE = 2              # samples per pixel along each axis, for images
REFERENCE_HEIGHT = 1080      # text sizes below are at this slide height
TITLE_PX, LABEL_PX, NOTE_PX = 46, 32, 28
TITLE_H, LABEL_H, LEGEND_H = 72, 50, 56
MARGIN = 14                  # pixels around and between panels at 1080p

# The scheme: one colour per idea, the same in every picture (sRGB uint8).
def _srgb(linear) -> tuple[int, int, int]:
    return tuple(int(c) for c in encode_srgb(np.array([[linear]], np.float64))[0, 0])


SCHEME = {
    "light": (255, 214, 0),
    "silhouette": (220, 20, 60),
    "side": _srgb(ROLE_COLOURS["side"]),
    "near cap": _srgb(ROLE_COLOURS["near cap"]),
    "far cap": _srgb(ROLE_COLOURS["far cap"]),
    "error": tuple(int(c) for c in pictures.ERROR_TINT),
    "eye": (30, 110, 230),
    "ray": (30, 110, 230),
    "occluder": (70, 90, 160),
    "plus": (0, 140, 60),
    "minus": (200, 30, 40),
    "ink": (20, 20, 24),
    "title": (40, 40, 48),
}

# Stencil counts: 0 is the lit image itself; then hues far apart, so 2 and 3 never look alike.
COUNT_COLOURS = np.array([[255, 225, 50], [245, 130, 30], [215, 35, 45], [150, 40, 170],
                          [40, 90, 220], [0, 165, 165], [60, 170, 60], [120, 120, 120],
                          [30, 30, 30]], np.uint8)
NEGATIVE = np.array([60, 200, 255], np.uint8)


def count_colour(k: int) -> tuple[int, int, int]:
    """The scheme's colour for stencil count k (k >= 1; k < 0: NEGATIVE)."""
    c = NEGATIVE if k < 0 else COUNT_COLOURS[min(k, len(COUNT_COLOURS)) - 1]
    return tuple(int(x) for x in c)


@dataclass(frozen=True)
class Layout:
    """A slide's size and the sizes of everything on it."""

    width: int = SLIDE[0]
    height: int = SLIDE[1]
    supersample: int = SUPERSAMPLE

    def px(self, at_1080: float) -> int:
        """A length given at 1080p, at this slide's height."""
        return max(1, round(at_1080 * self.height / REFERENCE_HEIGHT))

    @property
    def title_h(self) -> int:
        return self.px(TITLE_H)

    @property
    def label_h(self) -> int:
        return self.px(LABEL_H)

    @property
    def legend_h(self) -> int:
        return self.px(LEGEND_H)

    @property
    def margin(self) -> int:
        return self.px(MARGIN)

    def cell(self, cols: int, rows: int, legend: bool = False, labels: bool = True,
             side: int = 0) -> tuple[int, int]:
        """(w, h) of each of cols x rows panels filling the slide (labels above each, a legend
        strip at the bottom when asked, `side` pixels kept free on the right)."""
        m = self.margin
        free_w = self.width - side - (cols + 1) * m
        free_h = (self.height - self.title_h - (self.legend_h if legend else 0)
                  - rows * (self.label_h if labels else 0) - (rows + 1) * m)
        return max(1, free_w // cols), max(1, free_h // rows)

    def text(self, text: str, width: int, *, px: float = LABEL_PX, height: int | None = None,
             dark: bool = False) -> np.ndarray:
        height = self.label_h if height is None else height
        return text_strip(text, width, height, self.px(px), dark=dark)

    def compose(self, title: str, grid: list[list[tuple[str, np.ndarray]]],
                legend: list[tuple[str, tuple]] | None = None,
                side: np.ndarray | None = None,
                below: np.ndarray | None = None) -> np.ndarray:
        """The slide: `title`, rows of (label, (h, w, 3) uint8) panels (a label of "" takes no
        strip), centred, `side` ((h, w, 3) uint8) at their right and `below` under them, the
        legend strip at the bottom.  Returns (height, width, 3) uint8 exactly."""
        m = self.margin
        slide = np.full((self.height, self.width, 3), 255, np.uint8)
        slide[:self.title_h] = self.text(title, self.width, px=TITLE_PX, height=self.title_h,
                                         dark=True)
        rows = []
        for r in grid:
            panels = []
            for label, img in r:
                panels.append(np.concatenate([self.text(label, img.shape[1]), img])
                              if label else img)
            h = max(p.shape[0] for p in panels)
            panels = [np.pad(p, ((0, h - p.shape[0]), (0, 0), (0, 0)), constant_values=255)
                      for p in panels]
            rows.append(pictures.row(panels, gap=m))
        w = max(r.shape[1] for r in rows)
        rows = [np.pad(r, ((0, 0), (0, w - r.shape[1]), (0, 0)), constant_values=255)
                for r in rows]
        body = pictures.column(rows, gap=m)
        if side is not None:
            h = max(body.shape[0], side.shape[0])
            pad = lambda a: np.pad(a, ((0, h - a.shape[0]), (0, 0), (0, 0)), constant_values=255)
            body = pictures.row([pad(body), pad(side)], gap=m)
        if below is not None:
            w = max(body.shape[1], below.shape[1])
            pad = lambda a: np.pad(a, ((0, 0), (0, w - a.shape[1]), (0, 0)), constant_values=255)
            body = pictures.column([pad(body), pad(below)], gap=m)
        bottom = self.height - (self.legend_h if legend else 0)
        top = self.title_h + m
        bh, bw = min(body.shape[0], bottom - top), min(body.shape[1], self.width)
        x = (self.width - bw) // 2
        slide[top:top + bh, x:x + bw] = body[:bh, :bw]
        if legend:
            slide[bottom:] = self.legend(legend, self.width)
        return slide

    def legend(self, entries, width: int) -> np.ndarray:
        """(legend_h, width, 3) uint8: a swatch and its name per (label, colour), centred."""
        h, s = self.legend_h, self.px(LABEL_PX)
        f = font(s)
        strip = Image.new("RGB", (width, h), (255, 255, 255))
        draw = ImageDraw.Draw(strip)
        gap, sw = self.px(40), self.px(34)
        total = sum(sw + self.px(10) + draw.textlength(t, font=f) for t, _ in entries) + \
            gap * (len(entries) - 1)
        x = max(4, (width - total) / 2)
        y = (h - sw) // 2
        for text, colour in entries:
            draw.rectangle([x, y, x + sw, y + sw], fill=tuple(colour), outline=(0, 0, 0),
                           width=max(1, self.px(2)))
            x += sw + self.px(10)
            draw.text((x, (h - s) // 2 - 1), text, fill=(0, 0, 0), font=f)
            x += draw.textlength(text, font=f) + gap
        return np.asarray(strip, np.uint8)

    def note(self, lines: list[str], width: int, height: int,
             px: float = NOTE_PX) -> np.ndarray:
        """(height, width, 3) uint8: lines of text at `px` (at 1080p), top-left aligned."""
        img = Image.new("RGB", (width, height), (255, 255, 255))
        draw = ImageDraw.Draw(img)
        s = self.px(px)
        for i, line in enumerate(lines):
            draw.text((self.px(8), self.px(8) + i * round(1.35 * s)), line, fill=(0, 0, 0),
                      font=font(s))
        return np.asarray(img, np.uint8)


# ---------------------------------------------------------------------------------------------
# Scenes at panel size, supersampling
# ---------------------------------------------------------------------------------------------

def fit(scene, width: int, height: int, samples: int = 1, cover: bool = False):
    """`scene` at (width * samples, height * samples), its vertical field of view widened
    when the panel is narrower than the scene, so the scene's whole view stays in frame
    (`cover`: kept, so the sides are cut instead and the scene fills the height)."""
    camera = scene.camera
    aspect = width / height
    if camera.matrix_form:
        return _fit_matrices(scene, width * samples, height * samples,
                             aspect < scene.aspect and not cover)
    if aspect < scene.aspect and not cover:
        half = np.tan(np.radians(camera.fov_y) / 2) * scene.aspect / aspect
        camera = replace(camera, fov_y=float(np.degrees(2 * np.arctan(half))))
    return scene.replace(width=width * samples, height=height * samples, camera=camera)


def _fit_matrices(scene, width: int, height: int, by_width: bool):
    """`fit` of a camera given by matrices: its image scaled by one factor (the pixels keep
    their shape), the scene's width onto the panel's when `by_width`, else its height (as a
    look-at camera keeps fov_y), and centred on the panel."""
    c = scene.camera
    s = width / scene.width if by_width else height / scene.height
    camera = replace(c, fx=c.fx * s, fy=c.fy * s, cx=c.cx * s + (width - scene.width * s) / 2,
                     cy=c.cy * s + (height - scene.height * s) / 2)
    return scene.replace(width=width, height=height, camera=camera)


def downsample(linear: np.ndarray, samples: int) -> np.ndarray:
    """(H*s, W*s, C) -> (H, W, C) float: the mean of each s x s block (a box filter)."""
    if samples == 1:
        return np.asarray(linear)
    h, w = linear.shape[0] // samples, linear.shape[1] // samples
    return linear[:h * samples, :w * samples].reshape(h, samples, w, samples, -1).mean(
        axis=(1, 3))


def supersampled(render, scene, width: int, height: int, samples: int,
                 cover: bool = False) -> np.ndarray:
    """(height, width, 3) uint8 sRGB: `render(scene)` (a function returning linear RGB) at
    `samples` x the panel size (see `fit`), box-filtered down."""
    return encode_srgb(downsample(render(fit(scene, width, height, samples, cover)), samples))


# ---------------------------------------------------------------------------------------------
# Marks drawn over 3D pictures: the light, projected points, polygons
# ---------------------------------------------------------------------------------------------

def project(scene, points4: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n, 4) homogeneous world points -> (n, 2) pixel coordinates of `scene`'s image (x right,
    y down) and (n,) clip w (> 0: in front of the eye)."""
    clip = np.asarray(points4, np.float64) @ view_projection(scene.camera, scene.size).T
    w = clip[:, 3]
    safe = np.where(np.abs(w) < 1e-12, 1e-12, w)
    ndc = clip[:, :2] / safe[:, None]
    xy = np.stack([(ndc[:, 0] + 1) / 2 * scene.width, (1 - ndc[:, 1]) / 2 * scene.height], 1)
    return xy, w


def mark_lights(image: np.ndarray, scene, layout: Layout, lights=None) -> np.ndarray:
    """`image` ((H, W, 3) uint8 of `scene` at its size) with every light marked: a point or
    spot light as a yellow disc with a dark ring and "L" where it projects; an area light as
    its outline, a yellow dot per sample and "L" beside it (`_mark_area`); either as an arrow
    at the border toward it when off screen or behind; a directional light as an arrow, in the
    top right corner, along its direction projected into the image."""
    lights = scene.lights if lights is None else lights
    img = Image.fromarray(image)
    draw = ImageDraw.Draw(img)
    r = layout.px(24)
    ink, yellow = SCHEME["ink"], SCHEME["light"]
    h, w = image.shape[:2]
    for k, light in enumerate(lights):
        area = hasattr(light, "positions")
        if area or hasattr(light, "position"):
            xy, cw = project(scene, np.append(light.center if area else light.position,
                                              1.0)[None])
            x, y, cw = float(xy[0, 0]), float(xy[0, 1]), float(cw[0])
            if cw > 0 and 0 <= x < w and 0 <= y < h:
                if area:
                    _mark_area(draw, scene, light, layout)
                    continue
                draw.ellipse([x - r, y - r, x + r, y + r], fill=yellow, outline=ink,
                             width=max(1, layout.px(4)))
                draw.text((x, y), "L", fill=ink, font=font(layout.px(32)), anchor="mm")
                continue
            # off screen: an arrow at the border toward where it would be
            d = np.array([x - w / 2, y - h / 2]) * (1 if cw > 0 else -1)
            d /= max(np.linalg.norm(d), 1e-9)
            # the arrow's tip a marker's radius inside the border
            reach = min((w / 2 - r) / max(abs(d[0]), 1e-9), (h / 2 - r) / max(abs(d[1]), 1e-9))
            tip = np.array([w / 2, h / 2]) + d * reach
            _arrow(draw, tip - d * (layout.px(60) + layout.px(20)), d, layout)
        else:
            centre = np.array([w - 3 * r, 3 * r + k * 5 * r], float)
            p = scene.camera.target
            (a, b), _ = project(scene, np.array([[*p, 1.0], [*(p + light.direction), 1.0]]))
            d = b - a
            d = d / max(np.linalg.norm(d), 1e-9)
            draw.ellipse([*(centre - r), *(centre + r)], fill=yellow, outline=ink,
                         width=max(1, layout.px(4)))
            _arrow(draw, centre + d * r * 1.3, d, layout)
    return np.asarray(img, np.uint8)


def area_outline(light, n: int = 48) -> np.ndarray:
    """(k, 3) world points around an area light's edge: a rect's four corners, a disk's rim
    (n points); none (k = 0) for a sphere, whose samples lie on its surface."""
    if light.shape == "sphere":
        return np.zeros((0, 3))
    u, v = default_plane_axes(light.normal)
    if light.shape == "rect":
        a, b = light.size / 2
        return np.array([light.center + su * a * u + sv * b * v
                         for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
    phi = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return light.center + light.radius * (np.cos(phi)[:, None] * u + np.sin(phi)[:, None] * v)


def _mark_area(draw, scene, light, layout: Layout) -> None:
    """An area light in view: its outline (dark, over a pale fill, so its size reads), a
    yellow dot with a dark ring per sample, and "L" beside it, left of the outline."""
    ink, yellow = SCHEME["ink"], SCHEME["light"]
    edge = area_outline(light)
    pts = np.concatenate([edge, light.positions])
    xy, cw = project(scene, np.c_[pts, np.ones(len(pts))])
    if not (cw > 0).all():
        return
    if len(edge):
        poly = [tuple(p) for p in xy[:len(edge)]]
        draw.polygon(poly, fill=(255, 246, 200), outline=ink, width=max(1, layout.px(3)))
    dot = max(2, layout.px(6 if len(light.positions) <= 16 else 4))
    for x, y in xy[len(edge):]:
        draw.ellipse([x - dot, y - dot, x + dot, y + dot], fill=yellow, outline=ink,
                     width=max(1, layout.px(2)))
    left, mid = float(xy[:, 0].min()), float(xy[:, 1].mean())
    draw.text((left - layout.px(10), mid), "L", fill=ink, font=font(layout.px(32)), anchor="rm")


def _arrow(draw, start: np.ndarray, d: np.ndarray, layout: Layout) -> None:
    length, head = layout.px(60), layout.px(20)
    end = start + d * length
    n = np.array([-d[1], d[0]])
    draw.line([tuple(start), tuple(end)], fill=SCHEME["ink"], width=layout.px(6))
    draw.polygon([tuple(end + d * head), tuple(end + n * head * 0.6),
                  tuple(end - n * head * 0.6)], fill=SCHEME["light"], outline=SCHEME["ink"])


def clip_near(points4: np.ndarray, w_min: float = 1e-6) -> np.ndarray:
    """A convex polygon's (n, 4) clip-space corners cut to w >= w_min (Sutherland-Hodgman)."""
    out = []
    n = len(points4)
    for i in range(n):
        a, b = points4[i], points4[(i + 1) % n]
        ina, inb = a[3] >= w_min, b[3] >= w_min
        if ina:
            out.append(a)
        if ina != inb:
            t = (w_min - a[3]) / (b[3] - a[3])
            out.append(a + t * (b - a))
    return np.array(out).reshape(-1, 4)


def polygon_pixels(scene, corners4: np.ndarray) -> np.ndarray:
    """(n, 4) homogeneous world corners (w = 0: at infinity) of a convex polygon -> (k, 2)
    pixel coordinates of its part in front of the eye (k = 0 when none is)."""
    clip = np.asarray(corners4, np.float64) @ view_projection(scene.camera, scene.size).T
    clip = clip_near(clip)
    if len(clip) == 0:
        return np.zeros((0, 2))
    ndc = clip[:, :2] / clip[:, 3:4]
    return np.stack([(ndc[:, 0] + 1) / 2 * scene.width, (1 - ndc[:, 1]) / 2 * scene.height], 1)
