"""`shadowvol render` end to end, and the teaching views."""

from __future__ import annotations

import numpy as np
import pytest
from builders import tiny_scene
from PIL import Image

from shadowvol.cli.main import main as shadowvol_main
from shadowvol.io import load_masks
from shadowvol.pictures import HEAT_PALETTE, NEGATIVE_COLOUR, caption_px, heat_map
from shadowvol.raster.platform.context import ContextError
from shadowvol.raster.overlay import ROLE_COLOURS
from shadowvol.raster.renderer import Renderer

pytestmark = pytest.mark.gl  # renders through the CLI in this process


SCENE = """
name = "cli"
[image]
width = 64
height = 48
[camera]
eye = [0.0, 3.0, 5.0]
target = [0.0, 0.5, 0.0]
[[lights]]
type = "point"
position = [1.0, 4.0, 1.0]
[[lights]]
type = "directional"
direction = [0.3, -1.0, -0.2]
[[objects]]
type = "plane"
size = [8.0, 8.0]
[[objects]]
type = "box"
center = [0.0, 0.5, 0.0]
"""


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "cli.toml"
    path.write_text(SCENE)
    return path


def test_render_writes_every_output(ctx, scene_file, tmp_path, capsys):
    out = {k: tmp_path / f"{k}.{ext}" for k, ext in
           [("image", "png"), ("masks", "npz"), ("volumes", "png"), ("stencil", "png")]}
    code = shadowvol_main(["render", str(scene_file), "-o", str(out["image"]), "--method", "zfail",
                     "--silhouettes", "gpu", "--masks", str(out["masks"]), "--volumes",
                     str(out["volumes"]), "--stencil", str(out["stencil"])])
    assert code == 0, capsys.readouterr().err
    assert Image.open(out["image"]).size == (64, 48)
    # the teaching views: a title strip over each panel, the legend below
    strip = round(1.6 * caption_px(48))
    volumes = np.asarray(Image.open(out["volumes"]))
    legend_h = volumes.shape[0] - strip - 48
    assert volumes.shape[1] == 64 and legend_h >= strip
    stencil = np.asarray(Image.open(out["stencil"]))
    assert stencil.shape[1] == 2 * 64 + 4 and stencil.shape[0] > strip + 48 + strip  # two lights
    lit, coverage = load_masks(out["masks"])
    assert lit.shape == (2, 48, 64) and lit.dtype == bool and coverage.dtype == bool
    from shadowvol.scenefile import load_scene

    with Renderer(load_scene(scene_file), ctx) as r:
        expect = r.render("zfail", "gpu")
    np.testing.assert_array_equal(lit, expect.lit)
    np.testing.assert_array_equal(coverage, expect.coverage)
    assert (lit.sum(axis=(1, 2)) < coverage.sum()).all()  # the box casts a shadow for both


def test_teaching_views_have_titles_and_legends(ctx, scene_file, tmp_path):
    """--volumes and --stencil: the picture under a title strip naming the light(s) (dark
    text on white), the image itself unchanged beneath it, a legend strip of swatches below."""
    from shadowvol.cli.render import light_names, stencil_picture, volumes_picture
    from shadowvol.io import encode_srgb
    from shadowvol.scenefile import load_scene

    scene = load_scene(scene_file).replace(width=320, height=240)
    assert light_names(scene) == ["light 0 (point)", "light 1 (directional)"]
    with Renderer(scene, ctx) as r:
        frame = r.render(stencil=True)
        view = encode_srgb(r.volume_view())
    strip = round(1.6 * caption_px(240))
    for picture, panels in ((volumes_picture(view, scene, "auto"), [view]),
                            (stencil_picture(frame.stencil, encode_srgb(frame.image), scene),
                             None)):
        title = picture[:strip]
        assert (title < 100).all(axis=2).sum() > 200           # dark text: the title
        assert (title[:, :4] == 255).all()                     # on white
        legend = picture[strip + 240:]
        assert legend.shape[0] >= strip and (legend < 100).all(axis=2).sum() > 100
        if panels:
            np.testing.assert_array_equal(picture[strip:strip + 240], panels[0])
    stencil = stencil_picture(frame.stencil, encode_srgb(frame.image), scene)
    assert stencil.shape[1] == 2 * 320 + 4


def test_swatch_legend_wraps_to_the_width():
    from shadowvol.pictures import HEAT_LEGEND, swatch_legend

    one = swatch_legend(2000, HEAT_LEGEND, 18)
    narrow = swatch_legend(120, HEAT_LEGEND, 18)
    assert one.shape == (round(1.6 * 18), 2000, 3)
    assert narrow.shape[1] == 120 and narrow.shape[0] >= 3 * one.shape[0]   # several lines


def test_bad_scene_is_one_line_on_stderr_and_status_2(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[camera]\neye = [0, 0]\n")
    code = shadowvol_main(["render", str(bad), "-o", str(tmp_path / "x.png")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("error: ") and "bad.toml" in err and "Traceback" not in err
    assert not (tmp_path / "x.png").exists()


def test_missing_gl_is_reported_with_what_to_install(scene_file, tmp_path, capsys, monkeypatch):
    import shadowvol.cli.render

    def no_egl():
        raise ContextError("cannot create a headless EGL context (no EGL); install libegl1")

    monkeypatch.setattr(shadowvol.cli.render, "create_context", no_egl)
    code = shadowvol_main(["render", str(scene_file), "-o", str(tmp_path / "x.png")])
    assert code == 3  # rendering failed (not bad input): see shadowvol.cli.status
    assert capsys.readouterr().err.startswith("error: cannot create a headless EGL context")


def test_help_explains_every_option(capsys):
    with pytest.raises(SystemExit):
        shadowvol_main(["render", "--help"])
    text = capsys.readouterr().out
    for option in ("--output", "--method", "--silhouettes", "--masks", "--volumes", "--stencil",
                   "zpass", "zfail", "auto"):
        assert option in text


def test_heat_map_colours_counts():
    counts = np.array([[0, 1, 2, -1, 40]], np.int16)
    image = np.full((1, 5, 3), 200, np.uint8)
    out = heat_map(counts, image)
    np.testing.assert_array_equal(out[0, 0], [100, 100, 100])
    np.testing.assert_array_equal(out[0, 1], HEAT_PALETTE[0])
    np.testing.assert_array_equal(out[0, 2], HEAT_PALETTE[1])
    np.testing.assert_array_equal(out[0, 3], NEGATIVE_COLOUR)
    np.testing.assert_array_equal(out[0, 4], HEAT_PALETTE[-1])


def test_volume_view_tints_exactly_where_volumes_are_drawn(ctx):
    """No lights: the view is the image.  With the tiny scene's light, the side quads of the
    occluders cross the image, tinted toward the side colour; alpha (coverage) is untouched."""
    scene = tiny_scene().replace(width=32, height=32)
    with Renderer(scene.replace(lights=()), ctx) as r:
        plain = r.render().image
        np.testing.assert_array_equal(r.volume_view(), plain)
    with Renderer(scene, ctx) as r:
        image = r.render().image
        view = r.volume_view()
        coverage = r.target.read_colour()[..., 3] > 0.5
    changed = np.abs(view - image).max(axis=2) > 1e-6
    assert 0 < changed.sum() < changed.size
    side = np.array(ROLE_COLOURS["side"])
    toward = ((view - image)[changed] @ (side - side.mean())) > 0
    assert toward.mean() > 0.9
    assert coverage.all()
