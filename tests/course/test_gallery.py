"""The gallery: `shadowvol demo -o DIR --small` writes every picture as a slide and an
index.html that shows exactly those pictures in the course's order, and the pictures show what
their captions say."""

from __future__ import annotations

import re
from html.parser import HTMLParser

import numpy as np
import pytest
from PIL import Image

import raytrace
from shadowvol.cli.main import main
from shadowvol.course import (
    counting,
    demos_tracing,
    demos_volumes,
    slides,
    volume_roles,
)
from shadowvol.course import gallery as demo
from shadowvol.raster.renderer import Renderer
from shadowvol.raster.volumes.silhouettes import edge_multiplicity, side_quads, topology_signs
from shadowvol.raster.volumes.topology import Topology

pytestmark = pytest.mark.gl

EXPECTED = ["cage", "umbra_penumbra", "exact_penumbra", "hard_sum", "planar", "one_caster", "stack_stencil", "counting", "zpass_zfail",
            "whitted_best", "raytree", "tir", "shadow2d", "ray_plane", "compare",
            "shadow_mapping", "shadow_map_error", "rendering_equation", "ladder", "caustic", "aliasing",
            "glossy_dof"]   # the course's order


class _Index(HTMLParser):
    """The <img> sources and sizes in order, the TOC links, the <pre> texts of index.html."""

    def __init__(self):
        super().__init__()
        self.images, self.links, self.pre, self._in_pre = [], [], [], False

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.images.append((a["src"], int(a["width"]), int(a["height"])))
        elif tag == "a" and a.get("href", "").startswith("#"):
            self.links.append(a["href"][1:])
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


@pytest.fixture
def small(ctx):
    return demo.Gallery(small=True, ctx=ctx)


def test_index_shows_every_picture_once_in_the_course_order(gallery):
    out, index = gallery
    assert {p.name for p in out.iterdir()} == {f"{n}.png" for n in EXPECTED} | {"index.html"}
    assert [src for src, _, _ in index.images] == [f"{n}.png" for n in EXPECTED]
    assert index.links == EXPECTED                     # the table of contents, same order
    text = (out / "index.html").read_text(encoding="utf-8")
    headings = re.findall(r'<section id="section-(\w+)">', text)
    assert headings == [k for k, _ in demo.SECTIONS]
    assert headings[-2:] == ["outlook", "gi"]          # the course ends with the equation


@pytest.mark.parametrize("name", EXPECTED)
def test_each_picture_is_a_slide(gallery, name):
    out, index = gallery
    with Image.open(out / f"{name}.png") as im:
        assert im.format == "PNG" and im.mode == "RGB"
        assert im.size == slides.SMALL_SLIDE
        im.verify()
    _, w, h = next(i for i in index.images if i[0] == f"{name}.png")
    assert (w, h) == slides.SMALL_SLIDE
    pixels = np.asarray(Image.open(out / f"{name}.png"))
    layout = slides.Layout(*slides.SMALL_SLIDE)
    assert (pixels[1:layout.title_h - 1, -1] == slides.SCHEME["title"]).all()   # title strip
    assert pixels.std() > 10   # a picture, not a blank


def test_index_captions_and_commands(gallery):
    out, _ = gallery
    text = (out / "index.html").read_text(encoding="utf-8")
    for name in EXPECTED:
        figure = re.search(rf'<figure id="{name}">(.*?)</figure>', text, re.S)
        assert figure, name
        assert "Command: <code>" in figure.group(1) and "Shows: " in figure.group(1)
        assert text.count(f'src="{name}.png"') == 1
    assert "--small" in text


def test_ray_tree_and_exercises_printed(gallery):
    _, index = gallery
    tree = next(t for t in index.pre if t.startswith("#0 primary"))
    assert "hits 'glass ball'" in tree.splitlines()[0]
    assert {int(d) for d in re.findall(r"\[depth (\d+)", tree)} == {0, 1, 2}
    assert "refracted" in tree and "shadow -> light" in tree
    plane = next(t for t in index.pre if t.startswith("Ray:"))
    assert "= 1\n" in plane and "= (4, 4)" in plane
    assert any("total internal reflection" in t for t in index.pre)


def test_text_is_legible_at_1080p():
    layout = slides.Layout()                       # 1920 x 1080
    assert layout.px(slides.LABEL_PX) >= 28 and layout.px(slides.NOTE_PX) >= 28
    assert layout.px(slides.TITLE_PX) >= 40
    strip = slides.text_strip("Ag", 400, layout.label_h, layout.px(slides.LABEL_PX))
    ink = np.flatnonzero((strip < 128).any(axis=2).any(axis=1))
    assert ink.max() - ink.min() + 1 >= 28        # "A" cap height to "g" descender, in pixels


def test_supersampling_is_a_box_filter_and_fit_keeps_the_view():
    a = np.arange(4 * 6 * 3, dtype=np.float64).reshape(4, 6, 3)
    d = slides.downsample(a, 2)
    assert d.shape == (2, 3, 3)
    assert np.allclose(d[0, 0], a[:2, :2].mean(axis=(0, 1)))
    from builders import SCENES

    from shadowvol.scenefile import load_scene
    scene = load_scene(SCENES / "cage.toml")                      # 4:3
    narrow = slides.fit(scene, 300, 400)                          # 3:4
    half_w = lambda s: np.tan(np.radians(s.camera.fov_y) / 2) * s.aspect
    assert np.isclose(half_w(narrow), half_w(scene))              # the same horizontal view
    assert slides.fit(scene, 300, 400, 2).width == 600


def test_light_marker_is_where_the_light_projects(small):
    scene = slides.fit(demos_volumes.volume_roles.one_caster_scene(), 400, 300)
    blank = np.full((300, 400, 3), 255, np.uint8)
    marked = slides.mark_lights(blank, scene, small.layout)
    (x, y), = slides.project(scene, np.append(scene.lights[0].position, 1.0)[None])[0]
    r = small.layout.px(24)                                   # the marker's radius
    disc = marked[int(y) - r:int(y) + r + 1, int(x) - r:int(x) + r + 1]
    yellow = (np.abs(disc.astype(int) - slides.SCHEME["light"]).sum(axis=2) < 30)
    assert yellow.mean() > 0.3
    assert (marked != 255).any(axis=2).sum() < 0.05 * 400 * 300


def test_one_caster_roles_are_the_stencil_pass_polygons(small):
    scene = volume_roles.one_caster_scene()
    light4 = scene.lights[0].homogeneous
    r = volume_roles.roles(scene.objects[0], light4)
    assert len(r.silhouettes) == 6 and set(np.abs(r.multiplicity)) == {2}   # two-sided box
    assert len(r.near) + len(r.near_back) == 12 and len(r.far) == 12
    topo = Topology.build(scene.objects[0].vertices, scene.objects[0].faces)
    m = edge_multiplicity(topo, topology_signs(topo, light4))
    assert len(side_quads(topo, m, light4)) == 2 * len(r.sides)   # what the pass draws: m = 2
    picture = demos_volumes.one_caster(small)
    assert picture.numbers["silhouettes"] == 6 and picture.numbers["multiplicity"] == [2]


def test_stack_counts_textbook_one_ours_two(small):
    picture = demos_volumes.stack_stencil(small)
    n = picture.numbers
    assert {1, 2, 3, 4} <= set(n["textbook"])          # up to four slabs above a point
    assert {2, 4, 6, 8} <= set(n["ours"])               # every closed slab counts 2
    assert n["double_share"] > 0.98                     # ours = 2 x textbook (edges aside)
    # the textbook count is the ray tracer's: one slab straight above a floor point counts 1
    scene = small.scene("stack").replace(lights=(small.scene("stack").lights[0],))
    s = slides.fit(scene, 64, 48)
    counts, covered = demos_volumes.textbook_counts(s)
    with Renderer(s, small.ctx) as r:
        frame = r.render(stencil=True)
    assert ((counts > 0) == ~frame.lit[0])[covered & frame.coverage].mean() > 0.98


def test_counting_diagram_sums_match_the_point_test():
    """The crossings' sums against a direct test: z-fail = the volumes P lies in, z-pass =
    that minus the volumes the eye lies in (a point lies in the box's volume when the segment
    from it to the light crosses the box)."""
    def inside(p):
        box = counting.BOX
        t = np.linspace(0, 1, 20001)[:, None]
        q = p + t * (counting.LIGHT - p)
        hit = ((q[:, 0] > box[:, 0].min()) & (q[:, 0] < box[:, 0].max()) &
               (q[:, 1] > box[:, 1].min()) & (q[:, 1] < box[:, 1].max()))
        return int(hit.any())
    for _, eye, surface in counting.CASES:
        for volume, weight in ((counting.textbook_volume, 1), (counting.ours_volume, 2)):
            c = counting.counts(counting.crossings(eye, surface, volume(counting.LIGHT,
                                                                         counting.BOX)))
            assert c.zfail == weight * inside(surface)
            assert c.zpass == weight * (inside(surface) - inside(eye))
    # the lecture's two cases: right from outside, z-pass wrong from inside
    (_, e1, p1), (_, e2, p2) = counting.CASES
    assert inside(e1) == 0 and inside(p1) == 1 and inside(e2) == 1 and inside(p2) == 1


def test_zpass_error_is_marked_and_zfail_is_right(small):
    picture = demos_volumes.zpass_zfail(small)
    n = picture.numbers
    assert n["marked"] > 0 and n["zpass_interior"] > 0       # z-pass is wrong, not just at edges
    assert n["zfail_interior"] == 0                           # z-fail is right away from edges
    w, h = small.layout.cell(2, 2)
    s = slides.fit(small.scene("inside_shadow"), w, h)
    with Renderer(s, small.ctx) as r:
        zpass = r.render("zpass")
    ref_lit, _ = raytrace.shadow_masks(s)
    assert n["marked"] == int((zpass.lit != ref_lit).any(axis=0).sum())
    assert f"{n['marked']} pixels wrong" in picture.teaches


def test_planar_demo_shows_what_projection_misses(small):
    picture = demos_volumes.planar(small)
    w, h = small.layout.cell(3, 1, legend=True)
    assert picture.numbers["missing"] > 0.01 * w * w * 3 / 4   # the ball on the box, the cage
    assert picture.numbers["extra"] <= 0.001 * w * w * 3 / 4   # on the floor, both agree


def test_compare_slide_counts_the_band_and_the_interior(small):
    """The compare slide says where raster and ray tracer may differ (the ±1 px band along
    every edge) and what it measured: the band and the rest partition the panel, every
    mismatch lies on one of them, and the interior (the rest) differs nowhere."""
    n = demos_tracing.compare_picture(small).numbers
    assert n["band"] > 0 and n["band"] + n["interior_px"] == n["pixels"]
    assert n["band_differ"] + n["interior"] == n["mismatched"]
    assert n["interior"] == 0


def test_band_panel_tints_the_band_and_keeps_mismatches():
    from shadowvol.compare import maskdiff

    diff = np.array([[maskdiff.BOTH_LIT, maskdiff.BOTH_SHADOWED, maskdiff.SHADOWED_ONLY_IN_GOT,
                      maskdiff.BOTH_LIT]], np.uint8)
    band = np.array([[True, True, True, False]])
    out = demos_tracing.band_panel(diff, band)
    assert (out[0, :2] != diff[0, :2]).any(axis=1).all()          # the band: tinted
    np.testing.assert_array_equal(out[0, 2:], diff[0, 2:])        # a mismatch, off the band
    assert out[0, 0].sum() > out[0, 1].sum()                      # lit stays lighter
    grid = demos_tracing.pixel_grid(np.zeros((24, 36, 3), np.uint8), 3, 2)
    assert (grid[12] == 150).all() and (grid[:, 12] == 150).all() and (grid[5, 5] == 0).all()


def test_shadow_mapping_is_marked_worse_than_ours(small):
    n = demos_tracing.shadow_mapping(small).numbers
    assert n["pyrender_wrong"] > 10 * max(n["ours_wrong"], 1)


def test_crop_window_finds_the_cluster():
    where = np.zeros((40, 60), bool)
    where[30:34, 50:55] = True
    where[2, 3] = True
    x, y = demos_tracing.crop_window(where, 10, 8)
    assert x <= 50 and x + 10 >= 55 and y <= 30 and y + 8 >= 34


def test_centred_window_puts_a_lone_pixel_in_the_middle():
    where = np.zeros((40, 60), bool)
    where[30, 50] = True
    x, y = demos_tracing.centred_window(where, 10, 8)
    assert (x, y) == (45, 26)
    where[39, 59] = False
    where[:] = False
    where[39, 59] = True                                  # at the corner: kept in the image
    assert demos_tracing.centred_window(where, 10, 8) == (50, 32)


def test_other_slide_sizes(ctx, tmp_path):
    g = demo.Gallery(ctx=ctx, size=(640, 360))
    assert demos_tracing.tir(g).image.shape == (360, 640, 3)
    assert main(["demo", "-o", str(tmp_path / "g"), "--size", "12x5"]) == 2
    assert main(["demo", "-o", str(tmp_path / "g"), "--size", "big"]) == 2
    assert main(["demo", "-o", str(tmp_path / "g"), "--small", "--size", "640x360"]) == 2
    assert not (tmp_path / "g").exists()


def test_demo_without_scenes_folder_fails_cleanly(tmp_path, capsys):
    assert main(["demo", "-o", str(tmp_path / "g"), "--small",
                 "--scenes", str(tmp_path / "nothing")]) == 2
    assert "no scenes folder" in capsys.readouterr().err
    assert not (tmp_path / "g").exists()
