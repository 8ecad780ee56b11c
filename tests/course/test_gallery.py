"""The gallery: `shadowvol demo -o DIR --small` writes every picture and an index.html that
shows exactly those pictures, and the pictures show what their captions say."""

from __future__ import annotations

import re
from html.parser import HTMLParser

import numpy as np
import pytest
from builders import SCENES
from PIL import Image

import raytrace
from shadowvol.cli.main import main
from shadowvol.course import gallery as demo
from shadowvol.course import layout
from shadowvol.pictures import GAP, LEGEND_HEIGHT
from shadowvol.raster.renderer import Renderer
from shadowvol.scenefile import load_scene

EXPECTED = {"cage", "cage_volumes", "zpass_zfail", "stack_stencil", "planar", "shadow2d",
            "raytree", "whitted_best", "compare", "umbra_penumbra", "hard_sum"}
TITLE_BACKGROUND = (40, 40, 48)


class _Index(HTMLParser):
    """The <img> sources and sizes, and the <pre> texts, of index.html."""

    def __init__(self):
        super().__init__()
        self.images, self.pre, self._in_pre = {}, [], False

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.images[a["src"]] = (int(a["width"]), int(a["height"]))
        elif tag == "pre":
            self._in_pre = True
            self.pre.append("")

    def handle_endtag(self, tag):
        if tag == "pre":
            self._in_pre = False

    def handle_data(self, data):
        if self._in_pre:
            self.pre[-1] += data


@pytest.fixture(scope="module")
def gallery(tmp_path_factory):
    out = tmp_path_factory.mktemp("gallery")
    assert main(["demo", "-o", str(out), "--small"]) == 0
    index = _Index()
    index.feed((out / "index.html").read_text(encoding="utf-8"))
    return out, index


def small_size(name: str) -> tuple[int, int]:
    scene = load_scene(SCENES / f"{name}.toml")
    return scene.width // demo.SMALL_SCALE, scene.height // demo.SMALL_SCALE


def expected_size(name: str) -> tuple[int, int] | None:
    """(width, height) of the pictures whose layout the demo owns; None for those drawn by
    another module's figure (the ray tree, compare)."""
    s = layout.strip_height(small=True)
    g = GAP
    if name in ("cage", "cage_volumes", "whitted_best"):
        w, h = small_size("whitted_best" if name == "whitted_best" else "cage")
        return w, s + h
    if name == "zpass_zfail":
        w, h = small_size("inside_shadow")
        return 2 * w + g, s + 2 * (s + h) + g
    if name == "stack_stencil":
        w, h = small_size("stack")
        lights = len(load_scene(SCENES / "stack.toml").lights)
        return lights * w + (lights - 1) * g, s + s + h + LEGEND_HEIGHT
    if name == "planar":
        w, h = small_size("planar")
        return 3 * w + 2 * g, s + s + h
    if name == "shadow2d":
        return 400, s + 400
    return None


def test_index_shows_exactly_the_pictures_written(gallery):
    out, index = gallery
    written = {p.name for p in out.iterdir()}
    assert written == {f"{n}.png" for n in EXPECTED} | {"index.html"}
    assert set(index.images) == {f"{n}.png" for n in EXPECTED}   # relative links, no others


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_each_picture_is_a_png_of_its_size(gallery, name):
    out, index = gallery
    with Image.open(out / f"{name}.png") as im:
        assert im.format == "PNG" and im.mode == "RGB"
        size = im.size
        im.verify()
    assert size == index.images[f"{name}.png"]
    if expected_size(name) is not None:
        assert size == expected_size(name)
    pixels = np.asarray(Image.open(out / f"{name}.png"))
    assert (pixels[1:layout.strip_height(True) - 1, -1] == TITLE_BACKGROUND).all()  # title strip
    assert pixels.std() > 10   # a picture, not a blank


def test_index_captions_and_commands(gallery):
    out, index = gallery
    text = (out / "index.html").read_text(encoding="utf-8")
    for name in EXPECTED:
        figure = re.search(rf'<figure id="{name}">(.*?)</figure>', text, re.S)
        assert figure, name
        assert "Command: <code>" in figure.group(1) and "Shows: " in figure.group(1)
    assert "--small" in text


def test_ray_tree_printed_to_depth_two(gallery):
    _, index = gallery
    assert len(index.pre) == 1
    tree = index.pre[0]
    first = tree.splitlines()[0]
    assert first.startswith("#0 primary") and "hits 'glass ball'" in first
    depths = {int(d) for d in re.findall(r"\[depth (\d+)", tree)}
    assert depths == {0, 1, 2}
    assert "refracted" in tree and "shadow -> light" in tree


def test_zpass_error_is_marked_and_zfail_is_right(ctx, gallery):
    out, _ = gallery
    g = demo.Gallery(small=True, ctx=ctx)
    picture = demo.zpass_zfail(g)
    n = picture.numbers
    assert n["marked"] > 0 and n["zpass_interior"] > 0       # z-pass is wrong, not just at edges
    assert n["zfail_interior"] == 0                           # z-fail is right away from edges
    # the marked count is the pixels whose z-pass mask disagrees with the ray tracer
    scene = g.scene("inside_shadow")
    with Renderer(scene, ctx) as r:
        zpass = r.render("zpass")
    ref_lit, _ = raytrace.shadow_masks(scene)
    assert n["marked"] == int((zpass.lit != ref_lit).any(axis=0).sum())
    # and exactly those pixels are tinted in the written picture: the bottom-right panel is
    # the top-left one (z-pass) with the marked pixels changed
    pixels = np.asarray(Image.open(out / "zpass_zfail.png"))
    w, h = small_size("inside_shadow")
    s, gap = layout.strip_height(True), GAP
    top_left = pixels[2 * s:2 * s + h, :w]
    bottom_right = pixels[2 * s + h + gap + s:, w + gap:]
    assert bottom_right.shape == top_left.shape
    assert int((bottom_right != top_left).any(axis=2).sum()) == n["marked"]
    assert f"{n['marked']} pixels wrong" in picture.teaches


def test_planar_demo_shows_what_projection_misses(ctx):
    picture = demo.planar(demo.Gallery(small=True, ctx=ctx))
    w, h = small_size("planar")
    assert picture.numbers["missing"] > 0.01 * w * h       # the ball on the box, the cage inside
    assert picture.numbers["extra"] <= 0.001 * w * h       # on the floor, both agree


def test_demo_without_scenes_folder_fails_cleanly(tmp_path, capsys):
    assert main(["demo", "-o", str(tmp_path / "g"), "--small",
                 "--scenes", str(tmp_path / "nothing")]) == 2
    assert "no scenes folder" in capsys.readouterr().err
    assert not (tmp_path / "g").exists()
