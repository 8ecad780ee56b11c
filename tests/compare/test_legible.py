"""The labels of compare's picture and of raytrace masks' ground-truth picture are legible when
the picture is put on a slide: text at least 2 % of the picture's height (pictures.legible_rows),
measured on the pixels: the ink of a title, from its ascenders to its descenders."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from builders import ROOT

from shadowvol.compare.comparison import compare
from shadowvol.pictures import ground_truth_picture
MIN_TEXT_FRACTION = 0.02
from shadowvol.scenefile import load_scene

# DejaVu Sans: from the top of 'l' or 'd' to the bottom of 'p' or 'g' is 0.93 em (ascender 0.76
# + descender 0.24 at hinting); 0.85 leaves room for rounding at small sizes
INK_PER_EM = 0.85


def title_ink(picture: np.ndarray, panel_top: int, x0: int, x1: int) -> int:
    """Height in pixels of the dark text in the white strip right above the panel that starts at
    row `panel_top`, columns x0:x1 (the strip ends where the rows stop being mostly white)."""
    y = panel_top - 1
    while y >= 0 and (picture[y, x0:x1] > 200).mean() > 0.5:
        y -= 1
    strip = picture[y + 1:panel_top, x0:x1]
    ink = np.nonzero((strip < 100).all(axis=2).any(axis=1))[0]
    assert ink.size, "no text above the panel"
    return int(ink[-1] - ink[0] + 1)


def panel_top(picture: np.ndarray, panel: np.ndarray, x: int) -> int:
    h, w = panel.shape[:2]
    tops = [y for y in range(picture.shape[0] - h + 1)
            if np.array_equal(picture[y:y + h, x:x + w], panel)]
    assert tops, "panel not found"
    return tops[0]


def test_compare_picture_text_is_legible_on_a_slide(ctx):
    from shadowvol.compare import maskdiff

    scene = load_scene(ROOT / "scenes" / "stack.toml").replace(width=640, height=480)
    c = compare(scene, ctx=ctx)
    pic = c.picture()
    assert len(c.lights) == 2
    W = c.width
    for i in range(2):
        panel = maskdiff.diff_panel(c.raster_lit[i], c.raster_coverage, c.ref_lit[i],
                                    c.ref_coverage)
        x = 2 * (W + 4)
        ink = title_ink(pic, panel_top(pic, panel, x), x, x + W)  # "diff: ... px, ..."
        assert ink >= INK_PER_EM * MIN_TEXT_FRACTION * pic.shape[0], (ink, pic.shape)


def test_ground_truth_picture_text_is_legible_on_a_slide():
    h, w, lights = 480, 640, 3
    rng = np.random.default_rng(0)
    coverage = np.ones((h, w), bool)
    truth = SimpleNamespace(
        lit=rng.random((lights, h, w)) < 0.5, coverage=coverage,
        depth=rng.random((h, w)).astype(np.float32) + 1, normal=None,
        object_id=rng.integers(0, 3, (h, w)).astype(np.int32),
        facing=rng.random((lights, h, w)) < 0.5, casters=None)
    pic = ground_truth_picture(truth, ["floor", "box", "ball"])
    rows = 1 + lights
    assert pic.shape[0] > rows * h
    from shadowvol.pictures import depth_image
    ink = title_ink(pic, panel_top(pic, depth_image(truth.depth), 0), 0, w)  # "depth"
    assert ink >= INK_PER_EM * MIN_TEXT_FRACTION * pic.shape[0], (ink, pic.shape)
