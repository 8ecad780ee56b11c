"""The course's soft-shadow pictures (shadowvol.course.soft_gallery): what they count."""

from __future__ import annotations

import pytest

from shadowvol.course.gallery import Gallery
from shadowvol.course.soft_gallery import hard_sum, umbra_penumbra


@pytest.fixture(scope="module")
def pictures(gl_session):
    g = Gallery(small=True, ctx=gl_session)
    try:
        yield umbra_penumbra(g), hard_sum(g)
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
