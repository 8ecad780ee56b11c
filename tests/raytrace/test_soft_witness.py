"""Property: the ray tracer's soft-shadow counts against the float64 witness (tests/exact.py
`count_report`), on random area-light scenes (tests/strategies.py `area_light_scenes`: rect,
disk and sphere lights; closed, open and non-manifold casters; the camera often inside an
object or its volumes; lights grazing the floor or 1e-3 off a face; translations up to 1e5).

The rule is CONVENTIONS.md's: equal counts wherever no sample's hard edge lies within one
pixel, and nowhere a count outside what moving every sample's hard edge by one pixel allows.
`exact.check_lit_count` takes any renderer's lit_count: tests/raster/test_soft_witness_raster.py
checks the rasterizer's by the same property.  Profiles as for the other property tests
(HYPOTHESIS_PROFILE=ci, the default, a few seconds; long, by hand).  A failing scene is saved
as test-output/soft-witness/failing-raytrace.json.
"""

from __future__ import annotations

from exact import check_lit_count, lost_bound
from hypothesis import given, settings
from strategies import PROFILE, area_light_scenes, profile

from raytrace.soft import lit_counts


@settings(profile(), max_examples=40 if PROFILE == "ci" else 600)
@given(scene=area_light_scenes())
def test_ray_tracer_counts_match_the_witness(scene):
    count, _ = lit_counts(scene)
    check_lit_count(scene, count, "raytrace", lost_bound(scene))
