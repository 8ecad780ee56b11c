"""The gallery's last chapter (shadowvol.course.demos_outlook): the rendering equation with its
terms named, the ladder with every rung, the caustic, aliasing, glossy and depth of field, at
slide size; without scipy the ladder and the caustic are left out.  GL-free: none of them
rasterizes."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from shadowvol.cli.ladder import main as ladder_main
from shadowvol.course import demos_outlook, equation_picture, gallery, ladder, slides
from shadowvol.pictures import font

LECTURE_RUNGS = ["local illumination", "Whitted", "direct light", "path tracing", "photon map",
                 "radiosity"]   # the lecture's ladder, in its order
NAMES = ["rendering_equation", "ladder", "caustic", "aliasing", "glossy_dof"]


@pytest.fixture(scope="module")
def pictures():
    g = gallery.Gallery(small=True)
    try:
        return {demo.__name__: demo(g) for demo in demos_outlook.DEMOS}
    finally:
        g.release()


def test_the_chapter_is_the_gallery_s_last_section_in_the_lecture_s_order(pictures):
    assert [d.__name__ for d in demos_outlook.DEMOS] == NAMES
    assert gallery.DEMOS[-len(NAMES):] == demos_outlook.DEMOS
    assert gallery.SECTIONS[-1][0] == demos_outlook.SECTION == "gi"
    for name, p in pictures.items():
        assert p.name == name and p.section == "gi"
        assert p.image.shape == (*slides.SMALL_SLIDE[::-1], 3) and p.image.dtype == np.uint8
        assert p.teaches and p.shows and p.command and p.title
        assert p.image.std() > 10


def test_the_equation_names_every_term():
    labels = {label for _, _, label, _ in equation_picture.TERMS if label}
    assert labels == {"outgoing radiance", "emitted", "BRDF", "incoming radiance", "cosine"}
    assert "hemisphere" in equation_picture.INTEGRAL_LABEL
    assert "Kajiya 1986" in equation_picture.LINES[0]


def test_every_rung_of_the_ladder_is_there(pictures):
    assert [name.split(" ", 1)[1] for name, _ in ladder.RUNGS] == LECTURE_RUNGS
    assert [name.split(" ", 1)[0] for name, _ in ladder.RUNGS] == \
        [str(k) for k in range(1, len(LECTURE_RUNGS) + 1)]
    assert all(keeps.startswith("keeps") for _, keeps in ladder.RUNGS)
    assert pictures["ladder"].numbers["rungs"] == [name for name, _ in ladder.RUNGS]


def test_the_slide_shows_one_panel_per_rung():
    """Six flat rungs of six colours: each colour fills one square where `panel_size` puts
    it, in `RUNGS`' order, two rows of three."""
    layout = slides.Layout(*slides.SMALL_SLIDE)
    _, _, side = ladder.panel_size(layout)
    colours = 0.05 * np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [2, 2, 2], [1, 1, 0], [0, 1, 1]])
    images = [np.broadcast_to(c, (side, side, 3)) for c in colours]
    image = ladder.slide(images, np.ones(3), layout, "t")
    centres = []
    for c in ladder.display(images, np.ones(3)):
        where = np.all(image == c[0, 0], axis=2)
        ys = np.flatnonzero(where.sum(axis=1) >= side // 2)  # a square of it, side x side
        xs = np.flatnonzero(where.sum(axis=0) >= side // 2)
        assert len(ys) == len(xs) == side and np.ptp(ys) == np.ptp(xs) == side - 1
        centres.append((ys.mean(), xs.mean()))
    rows = [round(y) for y, _ in centres]
    assert rows[0] == rows[1] == rows[2] < rows[3] == rows[4] == rows[5]
    assert centres[0][1] < centres[1][1] < centres[2][1]


def test_the_rung_labels_fit_at_1080p_without_shrinking():
    layout = slides.Layout()
    w, _, side = ladder.panel_size(layout)
    assert side >= 350
    f = font(layout.px(slides.LABEL_PX))
    for name, keeps in ladder.RUNGS:
        for text in (name, keeps):
            assert f.getlength(text) <= w - 12, text


def test_the_ladder_command_draws_the_gallery_s_slide(pictures, tmp_path):
    from PIL import Image
    out = tmp_path / "ladder.png"
    assert ladder_main([str(gallery.SCENES / "cornell.toml"), "-o", str(out), "--small"]) == 0
    assert np.array_equal(np.asarray(Image.open(out)), pictures["ladder"].image)
    assert "python -m shadowvol.cli.ladder" in pictures["ladder"].command
    assert ladder_main([str(gallery.SCENES / "cornell.toml"), "-o", str(out),
                        "--spp", "0"]) == 2


def test_the_caustic_and_the_aliasing_pair_show_what_they_say(pictures):
    assert pictures["caustic"].numbers["caustic_photons"] > 100
    assert pictures["aliasing"].numbers["pixels_differ"] > 0
    assert "16 samples" in pictures["aliasing"].title


def test_without_scipy_the_ladder_and_the_caustic_are_left_out(monkeypatch):
    for name in ("scipy", "scipy.sparse", "scipy.spatial"):
        monkeypatch.setitem(sys.modules, name, None)
    monkeypatch.setattr(gallery, "DEMOS", demos_outlook.DEMOS)
    skipped = []
    made = gallery.build_gallery(small=True, skipped=skipped)
    assert [p.name for p in made] == ["rendering_equation", "aliasing", "glossy_dof"]
    assert [name for name, _ in skipped] == ["ladder", "caustic"]
    assert all("scipy" in why for _, why in skipped)
    assert "Left out: ladder" in gallery.index_html(made, True, skipped=skipped)
