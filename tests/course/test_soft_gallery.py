"""The course's soft-shadow pictures (shadowvol.course.soft_gallery): what they count."""

from __future__ import annotations

import numpy as np
import pytest

from shadowvol.course.gallery import Gallery
from shadowvol.course.soft_gallery import exact_penumbra, hard_sum, umbra_penumbra


@pytest.fixture(scope="module")
def pictures(gl_session):
    g = Gallery(small=True, ctx=gl_session)
    try:
        yield umbra_penumbra(g), hard_sum(g), exact_penumbra(g)
    finally:
        g.release()


def test_umbra_shrinks_and_penumbra_grows_with_the_light(pictures):
    counts = list(pictures[0].numbers.values())
    assert counts[0]["penumbra"] == 0 and counts[0]["umbra"] > 0  # the point light: hard
    umbra = [c["umbra"] for c in counts]
    penumbra = [c["penumbra"] for c in counts]
    assert all(b < a for a, b in zip(umbra, umbra[1:])), umbra
    assert all(b > a for a, b in zip(penumbra, penumbra[1:])), penumbra


def test_the_soft_shadow_is_the_sum_of_the_hard_ones(pictures):
    numbers = pictures[1].numbers
    assert numbers["levels"] == 5  # counts 0..4 all occur on screen
    assert numbers["penumbra"] > 0
    assert numbers["sum_error"] < 1e-5


def test_the_four_hard_shadows_visibly_part(pictures):
    """Each pair of the four samples' cast shadows differs in at least half as many pixels as
    the smaller of the two covers: the samples lie far apart on the light, so the shadows move,
    and all four still overlap somewhere (the umbra)."""
    numbers = pictures[1].numbers
    sizes, apart = numbers["shadow_px"], iter(numbers["apart_px"])
    assert len(sizes) == 4 and min(sizes) > 0
    for i in range(4):
        for j in range(i + 1, 4):
            assert next(apart) >= 0.5 * min(sizes[i], sizes[j]), (i, j, numbers)
    assert numbers["umbra"] > 0


def test_the_soft_slides_see_the_light_and_every_sample(gl_session):
    """The slides' camera has the largest light, its outline and every sample in the frame of
    each panel, so the legend's "a dot per sample" is drawn, not an arrow at the border."""
    from shadowvol.course import slides, soft_gallery

    g = Gallery(small=True, ctx=gl_session)
    scene = soft_gallery._ball_scene(g)
    big = soft_gallery._rect(scene.lights[0].center, max(soft_gallery.LIGHT_SIDES), 64)
    for cols, rows in ((2, 2), (3, 2)):
        s = slides.fit(scene, *g.layout.cell(cols, rows, legend=True))
        pts = np.concatenate([slides.area_outline(big), big.positions])
        xy, w = slides.project(s, np.c_[pts, np.ones(len(pts))])
        assert (w > 0).all()
        assert (xy >= 0).all() and (xy[:, 0] < s.width).all() and (xy[:, 1] < s.height).all()


def test_the_exact_penumbra_beside_the_sampled_ones(pictures):
    """The exact slide: a penumbra computed, and each sampled one's error over it (on the slide)
    falling with N, the largest within what the stratified grid allows (about 4/n for an
    n x n grid: 1, 0.5, 0.25) and not zero (the samples are a staircase)."""
    numbers = pictures[2].numbers
    assert numbers["penumbra"] > 200
    errors = [numbers[f"N = {n}"] for n in (16, 64, 256)]
    means = [e["mean"] for e in errors]
    assert all(b < a for a, b in zip(means, means[1:])), means
    assert all(0 < e["max"] <= 4 / n for e, n in zip(errors, (4, 8, 16))), errors
    # the exact penumbra is smooth: more distinct levels than 64 samples' staircase can have
    assert numbers["levels"]["exact"] > 65 and numbers["levels"]["N = 16"] <= 17, numbers
