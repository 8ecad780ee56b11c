"""The ray tree slide: one pixel's rays over the ray-traced image, the tree beside it as boxes,
a legend.  The gallery's `raytree` picture and `raytrace tree -o` draw it with this one
function, so the command's picture is the slide.

    tree = ray_tree(scene, x, y, max_depth=2)
    image = slide(Layout(), scene, tree, (x, y), 2, lambda s: raytrace.render(s, max_depth=2))

The boxes' text is the slide's 28 px (at 1080p) where the tree fits at that size, smaller for a
deep tree (`text_size`), never below `MIN_TEXT_PX`.
"""

from __future__ import annotations

import numpy as np
from raytrace.outlook.raytree import (
    BLOCKED,
    FACES_AWAY,
    LIT,
    OUTSIDE_CONE,
    REFLECTED,
    REFRACTED,
    TIR,
    RayNode,
    tree_colour,
)
from shadowvol import pictures
from shadowvol.course import raytree_diagram, slides
from shadowvol.scene import Scene

TEXT_PX = 28          # the boxes' and labels' text at 1080p
MIN_TEXT_PX = 9       # a deep tree's boxes shrink to this, no further
IMAGE_W = 780         # the image panel's width at 1080p (4:3 under it a note)


def legend(tree: RayNode) -> list[tuple[str, tuple]]:
    """The slide's legend: the rays' colours, as over the image and in the boxes (total
    internal reflection and untraced shadow rays where the tree has them)."""
    rgb = raytree_diagram.rgb
    seen = {n.kind for n in tree.walk()} | {n.verdict for n in tree.walk()}
    return ([("eye ray", (255, 255, 255)), ("reflected", rgb(REFLECTED)),
             ("refracted", rgb(REFRACTED))]
            + ([("total internal refl.", rgb(TIR))] if TIR in seen else [])
            + [("shadow ray: lit", rgb(LIT)), ("shadow ray: blocked", rgb(BLOCKED))]
            + ([("not traced", rgb(FACES_AWAY))] if seen & {FACES_AWAY, OUTSIDE_CONE}
               else []))


def fits(scene: Scene, tree: RayNode, width: int, height: int, text_px: int) -> bool:
    """Do the boxes of `tree` at `text_px`, placed as `raytree_diagram.draw_diagram` places
    them, fit a width x height diagram: inside it, no two boxes of a column touching, and
    at least 1.5 text heights between columns for the edges and their letters?"""
    boxes, where, gap = raytree_diagram.placed(scene, tree, width, height, text_px)
    if gap < 1.5 * text_px:
        return False
    spans: dict[int, list[tuple[float, float]]] = {}
    for b in boxes:
        _, y, h, _ = where[id(b.node)]
        spans.setdefault(b.column, []).append((y - h / 2, y + h / 2))
    clearance = 0.15 * text_px
    for column in spans.values():
        column.sort()
        if column[0][0] < 0 or column[-1][1] > height:
            return False
        if any(top < above + clearance for (_, above), (top, _) in zip(column, column[1:])):
            return False
    return True


def text_size(scene: Scene, tree: RayNode, width: int, height: int, largest: int) -> int:
    """The largest text size <= largest (and >= MIN_TEXT_PX) at which the tree `fits`."""
    px = largest
    while px > MIN_TEXT_PX and not fits(scene, tree, width, height, px):
        px -= 1
    return px


def traced_scene(L: slides.Layout, scene: Scene) -> Scene:
    """The scene as the slide traces its image: fitted to the image panel, at L.supersample
    (what a memory estimate of the picture needs)."""
    img_w = L.px(IMAGE_W)
    return slides.fit(scene, img_w, round(img_w * scene.height / scene.width), L.supersample)


def diagram_size(L: slides.Layout) -> tuple[int, int]:
    """(width, height) of the tree's panel on the slide."""
    return (L.width - L.px(IMAGE_W) - 3 * L.margin,
            L.height - L.title_h - L.legend_h - 2 * L.margin - L.label_h)


def slide(L: slides.Layout, scene: Scene, tree: RayNode, pixel: tuple[int, int], depth: int,
          render) -> np.ndarray:
    """(L.height, L.width, 3) uint8: the slide of `tree`, the ray tree of `pixel` (x, y) of
    `scene` to recursion depth `depth`; render(scene) -> (H, W, 3) linear RGB draws the image
    (called on the scene fitted to the panel, at L.supersample)."""
    text_px = L.px(TEXT_PX)
    img_w = L.px(IMAGE_W)
    img_h = round(img_w * scene.height / scene.width)
    s = slides.fit(scene, img_w, img_h)
    image = slides.supersampled(render, scene, img_w, img_h, L.supersample)
    image = raytree_diagram.draw_rays(image, s, tree, text_px)
    tree_w, body_h = diagram_size(L)
    note = L.note([f"{raytree_diagram.light_names(scene)}.",
                   "The pixel's colour is the sum of what",
                   "every ray adds, each weighted by the",
                   "reflectivity and transparency on its",
                   "path: " + "(" + ", ".join(f"{c:.3f}" for c in tree_colour(tree)) + ")."],
                  img_w, max(1, body_h - img_h - L.margin))
    left = pictures.column([image, note], gap=L.margin)
    box_px = text_size(scene, tree, tree_w, body_h, text_px)
    diagram = raytree_diagram.draw_diagram(scene, tree, tree_w, body_h, box_px)
    title = f"The ray tree of pixel ({pixel[0]}, {pixel[1]}), to recursion depth {depth}"
    return L.compose(title, [[("the rays over the image", left),
                              ("the tree: one box per ray", diagram)]], legend=legend(tree))
