"""The ray tree as a tree, for the gallery's slide: one box per ray, a row per generation.

    boxes = layout(tree)                                  # one Box per ray, in format_tree's order
    diagram = draw_diagram(scene, tree, 1000, 900, 28)    # (H, W, 3) uint8, left to right
    image = draw_rays(image, scene, tree, 28)             # the same rays over the render

The root (the eye ray) is at the left, its children in the next column and so on; each box says the
ray's number (as `raytrace.outlook.raytree.format_tree` prints it), its kind and what it meets, and
each edge is labelled with Whitted's letters: S a shadow ray, R the reflected ray, T the transmitted
(refracted) one.  Box colours are the rays' colours over the image (`COLOURS`), so the diagram and
the picture read together.  Pillow only.  The slide that puts the two side by side is
`raytree_slide`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from PIL import Image, ImageDraw

from raytrace.camera import camera_basis, pixel_focal
from raytrace.outlook.raytree import (
    BLOCKED,
    FACES_AWAY,
    LIT,
    OUTSIDE_CONE,
    PRIMARY,
    REFLECTED,
    REFRACTED,
    SHADOW,
    TIR,
    RayNode,
)
from shadowvol.pictures import font
from shadowvol.scene import DirectionalLight, Scene

COLOURS = {PRIMARY: "#ffffff", REFLECTED: "#00d0ff", REFRACTED: "#40e040", TIR: "#ff40ff",
           LIT: "#ffd000", BLOCKED: "#ff3030", FACES_AWAY: "#a0a0a0", OUTSIDE_CONE: "#a0a0a0"}
LETTERS = {SHADOW: "S", REFLECTED: "R", REFRACTED: "T", TIR: "R"}
INK = (20, 20, 24)
EDGE = (90, 90, 100)


def project(scene: Scene, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates (n, 2) float64 (x right, y down, pixel centres at +0.5) of world
    points (n, 3), and their eye-space depth (n,) (positive in front of the eye)."""
    right, up, back = camera_basis(scene.camera)
    rel = points - scene.camera.eye
    depth = -(rel @ back)
    fx, fy, cx, cy = pixel_focal(scene.camera, scene.width, scene.height)
    with np.errstate(divide="ignore", invalid="ignore"):
        px = fx * (rel @ right) / depth + cx
        py = cy - fy * (rel @ up) / depth
    return np.stack([px, py], axis=1), depth


def clip_near(scene: Scene, a: np.ndarray, b: np.ndarray):
    """The part of segment a-b in front of the near plane, or None."""
    _, (da, db) = project(scene, np.array([a, b]))
    near = scene.camera.near
    if da < near and db < near:
        return None
    if da < near:
        a = a + (near - da) / (db - da) * (b - a)
    elif db < near:
        b = b + (near - db) / (da - db) * (a - b)
    return a, b



@dataclass(frozen=True)
class Box:
    """One ray's box: its number, the node, its column (generation) and the centre of its row
    as a fraction of the diagram's height."""

    number: int
    node: RayNode
    column: int
    y: float


def rgb(key: str) -> tuple[int, int, int]:
    """`COLOURS[key]` (a ray kind or a shadow ray's verdict) as sRGB uint8."""
    c = COLOURS[key]
    return tuple(int(c[i:i + 2], 16) for i in (1, 3, 5))


def fill(node: RayNode) -> tuple[int, int, int]:
    """A box's fill: the ray's colour over the image (the eye ray: white)."""
    return rgb(node.verdict if node.kind == SHADOW else node.kind)


def lines(node: RayNode, number: int, scene: Scene) -> list[str]:
    """A box's text: a shadow ray's number, light and verdict on one line; another ray's
    number and kind, then what it meets (and, for reflected and refracted rays, the weight it
    counts with in the pixel)."""
    if node.kind == SHADOW:
        verdict = {LIT: "lit", BLOCKED: "blocked", FACES_AWAY: "not traced",
                   OUTSIDE_CONE: "not traced"}[node.verdict]
        return [f"#{number} L{node.light}: {verdict}"]
    name = {PRIMARY: "eye ray", REFLECTED: "reflected", REFRACTED: "refracted",
            TIR: "total int. refl."}[node.kind]
    meets = f"→ {node.obj_name}" if node.hit else "→ sky (miss)"
    out = [f"#{number} {name}", meets]
    if node.kind != PRIMARY:
        out.append(f"weight {node.weight:.2f}")
    return out


def layout(tree: RayNode) -> list[Box]:
    """Every ray of `tree` as a Box, numbered depth first like `format_tree`: leaves take one
    row each, top to bottom in that order (a shadow ray a short row), a parent is centred on
    its children's rows."""
    rows: list[tuple[int, RayNode, int]] = []      # (number, node, column)
    for number, node in enumerate(tree.walk()):
        rows.append((number, node, 0))
    column = {id(tree): 0}
    for node in tree.walk():
        for child in node.children:
            column[id(child)] = column[id(node)] + 1
    leaves = [n for n in tree.walk() if not n.children]
    heights = [0.6 if n.kind == SHADOW else 1.0 for n in leaves]
    total = sum(heights)
    centre, at = {}, 0.0
    for n, h in zip(leaves, heights):
        centre[id(n)] = (at + h / 2) / total
        at += h

    def place(node: RayNode) -> float:
        if id(node) not in centre:
            ys = [place(c) for c in node.children]
            centre[id(node)] = (ys[0] + ys[-1]) / 2
        return centre[id(node)]

    place(tree)
    return [Box(number, node, column[id(node)], centre[id(node)]) for number, node, _ in rows]


def placed(scene: Scene, tree: RayNode, width: int, height: int, text_px: int):
    """Where `draw_diagram` puts the boxes: (boxes, {id(node): (left x, centre y, height,
    width)}, the gap between columns), at text size text_px."""
    boxes = layout(tree)
    draw = ImageDraw.Draw(Image.new("RGB", (1, 1)))
    columns = max(b.column for b in boxes) + 1
    line_h = round(text_px * 1.25)
    box_w = [text_px + max(draw.textlength(t, font=font(text_px, bold=_bold(b, i)))
                           for b in boxes if b.column == c
                           for i, t in enumerate(lines(b.node, b.number, scene)))
             for c in range(columns)]
    gap = (width - text_px // 2 - sum(box_w)) / max(columns - 1, 1)
    left = [sum(box_w[:c]) + c * gap for c in range(columns)]
    pad = line_h * 2
    where = {}
    for b in boxes:
        h = len(lines(b.node, b.number, scene)) * line_h + text_px * 0.5
        y = pad + b.y * (height - 2 * pad)
        where[id(b.node)] = (left[b.column], y, h, box_w[b.column])
    return boxes, where, gap


def _bold(b: Box, i: int) -> bool:
    """Is line i of box b its title line (bold)?"""
    return i == 0 and b.node.kind != SHADOW


def draw_diagram(scene: Scene, tree: RayNode, width: int, height: int,
                 text_px: int) -> np.ndarray:
    """(height, width, 3) uint8: the tree left to right, a box per ray (see `layout`), edges
    from each box to its children's boxes with their letter (S, R, T) on them."""
    boxes, where, gap = placed(scene, tree, width, height, text_px)
    img = Image.new("RGB", (width, height), (255, 255, 255))
    draw = ImageDraw.Draw(img)
    letter = font(text_px, bold=True)
    line_h = round(text_px * 1.25)
    stroke = max(2, round(text_px / 9))
    for b in boxes:                                    # edges first, under the boxes
        x, y, h, bw = where[id(b.node)]
        for child in b.node.children:
            cx, cy, _, _ = where[id(child)]
            mid = x + bw + gap / 2
            draw.line([(x + bw, y), (mid, y), (mid, cy), (cx, cy)], fill=EDGE, width=stroke)
            draw.text((mid + (cx - mid) / 2, cy - stroke), LETTERS[child.kind], fill=INK,
                      font=letter, anchor="mb")
    for b in boxes:
        x, y, h, bw = where[id(b.node)]
        dotted = b.node.verdict in (FACES_AWAY, OUTSIDE_CONE)
        draw.rounded_rectangle([x, y - h / 2, x + bw, y + h / 2], radius=text_px // 3,
                               fill=fill(b.node), outline=(150, 150, 150) if dotted else INK,
                               width=stroke)
        text = lines(b.node, b.number, scene)
        for i, t in enumerate(text):
            ty = y - h / 2 + text_px * 0.25 + (i + 0.5) * line_h
            draw.text((x + text_px / 2, ty), t, fill=INK, anchor="lm",
                      font=font(text_px, bold=_bold(b, i)))
    return np.asarray(img, np.uint8)


def draw_rays(image: np.ndarray, scene: Scene, tree: RayNode, text_px: int) -> np.ndarray:
    """`image` ((H, W, 3) uint8 of `scene` at its size) with every ray of `tree` drawn through
    the camera in its colour (a dark rim under it), the pixel ringed and the eye, reflected and
    refracted rays' hits numbered as in `layout`."""
    img = Image.fromarray(image)
    draw = ImageDraw.Draw(img)
    width = max(2, round(text_px / 7))
    labels = []
    for number, node in enumerate(tree.walk()):
        if node.kind == PRIMARY:
            continue
        seg = clip_near(scene, node.origin, node.end)
        if seg is None:
            continue
        xy, _ = project(scene, np.array(seg))
        pts = [tuple(p) for p in xy]
        dotted = node.verdict in (FACES_AWAY, OUTSIDE_CONE)
        if not dotted:
            draw.line(pts, fill=INK, width=width + 4)
        draw.line(pts, fill=fill(node), width=width)
        if node.hit and node.kind != SHADOW:
            labels.append((f"#{number}", pts[1]))
    ((px, py),), _ = project(scene, np.array([tree.origin + tree.direction]))
    r = text_px * 0.6
    draw.ellipse([px - r, py - r, px + r, py + r], outline=(255, 255, 255), width=width + 1)
    labels.insert(0, ("#0", (px, py)))
    f = font(text_px, bold=True)
    taken = []

    def inside(b) -> bool:
        return b[0] >= 0 and b[1] >= 0 and b[2] <= img.width and b[3] <= img.height

    for text, (x, y) in labels:               # each label beside its point, clear of the others
        tries = []                            # and of the image's edges, where a place is
        for dx, dy in ((1, -1), (1, 1), (-1, -1), (-1, 1), (2, 0), (-2, 0)):
            at = (x + dx * r, y + dy * r)
            anchor = ("l" if dx > 0 else "r") + ("s" if dy < 0 else "t")
            box = draw.textbbox(at, text, font=f, anchor=anchor)
            tries.append((at, anchor, box))
        clear = [t for t in tries if not any(_overlap(t[2], o) for o in taken)]
        at, anchor, box = next((t for t in clear if inside(t[2])),
                               clear[0] if clear else tries[-1])
        taken.append(box)
        draw.text(at, text, fill=(255, 255, 255), font=f, anchor=anchor,
                  stroke_width=max(2, text_px // 10), stroke_fill=INK)
    return np.asarray(img, np.uint8)


def _overlap(a, b) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def light_names(scene: Scene) -> str:
    """"L0 the point light, L1 the directional light": what the boxes' L0, L1 are."""
    kinds = [("directional" if isinstance(lt, DirectionalLight) else type(lt).__name__
              .replace("Light", "").lower()) for lt in scene.lights]
    return ", ".join(f"L{i} the {k} light" for i, k in enumerate(kinds))
