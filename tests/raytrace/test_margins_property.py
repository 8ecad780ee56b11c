"""Property: every margin of the masks (the surface's lift, the shadow segment's start and end,
the light's own end) never skips geometry that a float64 walk of the segment meets.

Random scenes (tests/strategies.py `grazing_scenes`): a floor and closed, open and
non-manifold objects under lights at n·l̂ down to 1e-4, point lights 1e-5 .. 1e-3 off a face,
the whole translated by up to 1e5.  The ray tracer's `lit` and `coverage` must equal the
float64 brute force (tests/exact.py `exact_ties`) at every pixel where the brute force is not
within its own error bound of a tie; the margins' own bound (`lost`: LIFT_HEIGHTS heights, the
light margin) is the only other allowance.  Profiles as for the other property tests
(HYPOTHESIS_PROFILE=ci, the default, a few seconds; long, by hand).  A failing scene is saved
as test-output/margins-property/failing.json.
"""

from __future__ import annotations

from builders import TEST_OUTPUT
from exact import exact_ties, lost_bound
from hypothesis import given, note, settings
from strategies import PROFILE, grazing_scenes, profile

import raytrace
from shadowvol.scenefile import save_scene

OUT = TEST_OUTPUT / "margins-property"


def check_margins(scene) -> None:
    lit, cov = raytrace.shadow_masks(scene)
    ex_lit, ex_cov, tie = exact_ties(scene, lost_bound(scene))
    cov_bad = (cov != ex_cov) & ~tie.any(axis=0)
    lit_bad = (lit != ex_lit) & ~tie
    note(f"coverage {int(cov_bad.sum())}, lit {lit_bad.sum(axis=(1, 2)).tolist()}, "
         f"ties {tie.sum(axis=(1, 2)).tolist()}")
    if cov_bad.any() or lit_bad.any():
        path = OUT / "failing.json"
        save_scene(scene, path)  # overwritten while shrinking: the last one is the smallest
        raise AssertionError(f"ray tracer vs float64 walk outside ties: coverage "
                             f"{int(cov_bad.sum())}, lit {lit_bad.sum(axis=(1, 2)).tolist()}; "
                             f"saved as {path}")


@settings(profile(), max_examples=200 if PROFILE == "ci" else 2000)
@given(scene=grazing_scenes())
def test_margins_skip_nothing_a_float64_walk_meets(scene):
    check_margins(scene)
