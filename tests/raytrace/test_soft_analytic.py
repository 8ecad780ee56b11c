"""The analytic soft shadow: a square occluder parallel to a square light above a floor.

The exact visible fraction at a floor point is 1 - a product of two 1D overlaps
(`builders.square_visible_fraction`).  The ray tracer's count is checked twice: sample by
sample against the segments computed analytically, and as an estimate of the exact fraction,
within the bound the stratified grid gives and converging as N grows.
"""

from __future__ import annotations

import numpy as np
import pytest
from builders import (
    blocked_samples,
    floor_points,
    square_light,
    square_over_floor,
    square_visible_fraction,
    stratified_bound,
)

import raytrace

# A segment passing closer than this to the occluder's outline is a call float32 may decide
# either way (the masks trace in float32 at coordinates of ~4); none is counted against them.
GRAZING = 1e-5

GRIDS = [2, 4, 8, 16]


@pytest.fixture(scope="module")
def traced():
    """n -> (scene, SoftMasks) for the n x n stratified light, traced once."""
    out = {}
    for n in GRIDS:
        scene = square_over_floor(square_light(n * n, seed=n))
        out[n] = scene, raytrace.soft_masks(scene)
    return out


@pytest.mark.parametrize("n", GRIDS)
def test_counts_are_exact_per_sample(traced, n):
    scene, soft = traced[n]
    p, on_floor = floor_points(scene)
    blocked, margin = blocked_samples(p, scene.lights[0].positions)
    expected = n * n - blocked.sum(axis=-1)
    clear = on_floor & (margin.min(axis=-1) > GRAZING)
    assert clear.sum() > 0.9 * on_floor.sum()
    got = soft.lit_count[0]
    bad = clear & (got != expected)
    assert not bad.any(), f"{int(bad.sum())} pixels counted wrong, e.g. " \
                          f"{np.argwhere(bad)[:5].tolist()}"
    # and the shadow is really soft: umbra, penumbra and full light all occur on the floor
    assert soft.umbra[0][on_floor].any() and soft.lit[0][on_floor].any()
    assert soft.penumbra[0][on_floor].sum() > 50


@pytest.mark.parametrize("n", GRIDS)
def test_estimate_within_the_grid_bound(traced, n):
    scene, soft = traced[n]
    p, on_floor = floor_points(scene)
    error = np.abs(soft.visibility[0].astype(np.float64) - square_visible_fraction(p))
    bound = stratified_bound(p, n)
    clear = on_floor & (blocked_samples(p, scene.lights[0].positions)[1].min(axis=-1) > GRAZING)
    worst = (error - bound)[clear].max()
    assert worst <= 1e-6, f"estimate off the exact fraction by {worst} more than the bound"


def test_estimate_converges(traced):
    """Mean and largest error over the floor shrink with each fourfold N (4, 16, 64, 256),
    the largest no worse than the grid's bound, about 4/n for an n x n grid."""
    means, worsts = [], []
    for n in GRIDS:
        scene, soft = traced[n]
        p, on_floor = floor_points(scene)
        shadowed = on_floor & (square_visible_fraction(p) < 1.0)  # the light is cut here
        error = np.abs(soft.visibility[0] - square_visible_fraction(p))[shadowed]
        means.append(error.mean())
        worsts.append(error.max())
        bound = stratified_bound(p, n)[shadowed].max()
        assert worsts[-1] <= bound + 1e-6 and bound <= 4 / n
    assert all(b < a for a, b in zip(means, means[1:])), means
    assert all(b < a for a, b in zip(worsts, worsts[1:])), worsts
    assert means[-1] < 0.01, means
