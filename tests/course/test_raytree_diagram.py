"""The ray tree slide's diagram (shadowvol.course.raytree_diagram): a box per ray, in the tree's
shape, beside the rays drawn over the image."""

from __future__ import annotations

import numpy as np
import pytest
from builders import SCENES

from raytrace.outlook.raytree import PRIMARY, SHADOW, ray_tree
from shadowvol.course import raytree_diagram
from shadowvol.course.demos_tracing import RAY_TREE_DEPTH, ray_tree_pixel
from shadowvol.scenefile import load_scene


@pytest.fixture(scope="module")
def tree_and_scene():
    scene = load_scene(SCENES / "whitted.toml")
    x, y = ray_tree_pixel(scene, "glass ball")
    return ray_tree(scene, x, y, max_depth=RAY_TREE_DEPTH), scene


def test_a_box_per_ray_to_depth_two(tree_and_scene):
    """The glass ball's pixel at depth 2: the eye ray, 2 reflected, 2 refracted and a shadow
    ray per light at each of the 4 hits: 13 boxes, in 4 columns, numbered as format_tree."""
    tree, scene = tree_and_scene
    boxes = raytree_diagram.layout(tree)
    assert len(boxes) == 13 == len(list(tree.walk()))
    assert [b.number for b in boxes] == list(range(13))
    kinds = [b.node.kind for b in boxes]
    assert kinds.count(PRIMARY) == 1 and kinds.count(SHADOW) == 4 * len(scene.lights)
    assert kinds.count("reflected") == 2 and kinds.count("refracted") == 2
    assert {b.column for b in boxes} == {0, 1, 2, 3}


def test_the_layout_is_a_tree(tree_and_scene):
    """Leaves run top to bottom in the tree's order, each parent sits between its first and
    last child, one column left of them, and no two boxes of a column share a row."""
    tree, _ = tree_and_scene
    boxes = raytree_diagram.layout(tree)
    at = {id(b.node): b for b in boxes}
    leaves = [b.y for b in boxes if not b.node.children]
    assert leaves == sorted(leaves) and 0 < leaves[0] and leaves[-1] < 1
    for b in boxes:
        if b.node.children:
            ys = [at[id(c)].y for c in b.node.children]
            assert min(ys) <= b.y <= max(ys)
            assert all(at[id(c)].column == b.column + 1 for c in b.node.children)
    for column in {b.column for b in boxes}:
        ys = sorted(b.y for b in boxes if b.column == column)
        assert all(b - a > 0.05 for a, b in zip(ys, ys[1:]))


def test_diagram_and_rays_are_drawn_at_slide_size(tree_and_scene):
    tree, scene = tree_and_scene
    d = raytree_diagram.draw_diagram(scene, tree, 1000, 800, 28)
    assert d.shape == (800, 1000, 3)
    for node in tree.walk():                      # every box's colour is on the diagram
        assert (d == raytree_diagram.fill(node)).all(axis=2).sum() > 500
    image = np.full((scene.height, scene.width, 3), 128, np.uint8)
    drawn = raytree_diagram.draw_rays(image, scene, tree, 28)
    assert (drawn != 128).any(axis=2).mean() > 0.01
    assert raytree_diagram.light_names(scene) == "L0 the point light, L1 the directional light"


def test_a_deep_tree_shrinks_its_boxes_to_fit():
    """The glass ball's pixel at the scene's depth 5 (29 rays): at the slide's 28 px the boxes
    overflow the diagram, so `raytree_slide` takes the largest size at which they fit; the
    depth-2 tree keeps 28 px.  `fits` is the check: one pixel larger does not fit."""
    from shadowvol.course import raytree_slide
    from shadowvol.course.slides import Layout

    scene = load_scene(SCENES / "whitted.toml")
    x, y = ray_tree_pixel(scene, "glass ball")
    w, h = raytree_slide.diagram_size(Layout())
    deep = ray_tree(scene, x, y, max_depth=scene.max_depth)
    assert len(list(deep.walk())) > 20
    assert not raytree_slide.fits(scene, deep, w, h, raytree_slide.TEXT_PX)
    px = raytree_slide.text_size(scene, deep, w, h, raytree_slide.TEXT_PX)
    assert raytree_slide.MIN_TEXT_PX < px < raytree_slide.TEXT_PX
    assert raytree_slide.fits(scene, deep, w, h, px)
    assert not raytree_slide.fits(scene, deep, w, h, px + 1)
    shallow = ray_tree(scene, x, y, max_depth=RAY_TREE_DEPTH)
    assert raytree_slide.text_size(scene, shallow, w, h, 28) == 28


def test_the_slide_legend_names_what_the_tree_has():
    """Total internal reflection and untraced shadow rays are in the legend only where the
    tree has them."""
    from shadowvol.course import raytree_slide

    scene = load_scene(SCENES / "whitted.toml")
    x, y = ray_tree_pixel(scene, "glass ball")
    deep = [label for label, _ in raytree_slide.legend(ray_tree(scene, x, y, max_depth=5))]
    assert "not traced" in deep and deep[0] == "eye ray"
    one = [label for label, _ in raytree_slide.legend(ray_tree(scene, x, y, max_depth=0))]
    assert "not traced" not in one and "total internal refl." not in one
