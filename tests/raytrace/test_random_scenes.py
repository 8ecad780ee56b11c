"""Property: on random large worlds, the reference masks equal the float64 brute-force check
(tests/exact.py) away from edges: zero mismatches farther than one pixel from a mask edge.

The generators (tests/strategies.py) draw the scenes of tests/worlds.py: kerbs translated by
1e3..1e6 under a low sun, a lamp shade and a cube on a ground quad 1e5..1e7 wide, a card 2e-5
to 1e-2 wide beside a point light, grazing light at almost flat concave creases.  Profiles as
in test_robustness_property.py (HYPOTHESIS_PROFILE=ci, the default, or long).  A failing scene
is shrunk and saved as test-output/reference-property/failing-<kind>.json.
"""

from __future__ import annotations

from builders import TEST_OUTPUT
from exact import exact_masks
from hypothesis import given, note
from strategies import (
    cards_by_lights,
    far_kerbs,
    grazing_creases,
    huge_grounds,
    profile,
)

import raytrace
from shadowvol.compare.maskdiff import mask_report
from shadowvol.scenefile import save_scene

OUT = TEST_OUTPUT / "reference-property"


def check_reference(scene, kind: str) -> None:
    lit, cov = raytrace.shadow_masks(scene)
    report = mask_report(lit, cov, *exact_masks(scene))
    note(f"{kind}: {report}")
    if any(row["interior"] for row in report):
        path = OUT / f"failing-{kind}.json"
        save_scene(scene, path)  # overwritten while shrinking: the last one is the smallest
        raise AssertionError(f"{kind}: reference vs exact float64, interior mismatches "
                             f"{[(r['what'], r['interior']) for r in report]}; saved as {path}")


@profile()
@given(scene=far_kerbs())
def test_far_kerbs(scene):
    check_reference(scene, "kerbs")


@profile()
@given(scene=huge_grounds())
def test_huge_ground_quads(scene):
    check_reference(scene, "ground")


@profile()
@given(scene=cards_by_lights())
def test_cards_beside_point_lights(scene):
    check_reference(scene, "card")


@profile()
@given(scene=grazing_creases())
def test_grazing_creases(scene):
    check_reference(scene, "crease")
