"""Property: the ray tracer's soft-shadow counts against the float64 witness (tests/exact.py
`count_report`), on random area-light scenes (tests/strategies.py `area_light_scenes`: rect,
disk and sphere lights; closed, open and non-manifold casters; the camera often inside an
object or its volumes; lights grazing the floor or 1e-3 off a face; translations up to 1e5).

The rule is CONVENTIONS.md's: equal counts wherever no sample's hard edge lies within one
pixel, and nowhere a count outside what moving every sample's hard edge by one pixel allows.
`check_lit_count` takes any renderer's lit_count, so the rasterizer's can be checked by the
same property.  Profiles as for the other property tests (HYPOTHESIS_PROFILE=ci, the default,
a few seconds; long, by hand).  A failing scene is saved as test-output/soft-witness/
failing.json.
"""

from __future__ import annotations

from builders import TEST_OUTPUT
from exact import count_report, lost_bound
from hypothesis import given, note, settings
from strategies import PROFILE, area_light_scenes, profile

from raytrace.soft import lit_counts
from shadowvol.scenefile import save_scene

OUT = TEST_OUTPUT / "soft-witness"


def check_lit_count(scene, lit_count, who: str, lost: float) -> None:
    """Raise AssertionError (hypothesis shrinks it) where `who`'s lit_count (L, H, W) breaks
    the rule, a sample whose brute-force answer is a tie (within `lost`, the renderer's
    margin, or the brute force's own bound: `exact_ties`) going either way; the scene is saved
    first."""
    summary = [{k: r[k] for k in ("what", "interior", "outside", "total")}
               for r in count_report(scene, lit_count, lost=lost)]
    note(f"{who}: {summary}")
    if any(r["interior"] or r["outside"] for r in summary):
        path = OUT / f"failing-{who}.json"
        save_scene(scene, path)  # overwritten while shrinking: the last one is the smallest
        raise AssertionError(f"{who} vs the float64 witness: {summary}; saved as {path}")


@settings(profile(), max_examples=40 if PROFILE == "ci" else 600)
@given(scene=area_light_scenes())
def test_ray_tracer_counts_match_the_witness(scene):
    count, _ = lit_counts(scene)
    check_lit_count(scene, count, "raytrace", lost_bound(scene))
