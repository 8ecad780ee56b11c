"""Property: the rasterizer's soft-shadow counts against the float64 witness (tests/exact.py
`count_witness`, `check_lit_count`), in every mode that decides shadows differently: auto and
z-fail with CPU silhouettes, auto and z-fail with GPU silhouettes, on the random area-light
scenes of tests/strategies.py `area_light_scenes` (rect, disk and sphere lights; closed, open
and non-manifold casters; the camera often inside an object or its volumes; lights grazing the
floor or 1e-3 off a face; translations up to 1e5).  The rule is CONVENTIONS.md's, the same as
the ray tracer's (tests/raytrace/test_soft_witness.py), with the rasterizer's one exception:
pixels whose visible surface is a tie below GL's vertex precision (`exact.gl_vertex_ties`).
The rasterizer has no shadow-ray margin (lost 0: only the brute force's own ties go either
way).  HYPOTHESIS_PROFILE=long for the long run; a failing scene is saved under
test-output/soft-witness/.
"""

from __future__ import annotations

import pytest
from exact import check_lit_count, count_witness, gl_vertex_ties
from hypothesis import given, settings
from strategies import PROFILE, area_light_scenes, profile

from shadowvol.raster.renderer import Renderer

pytestmark = pytest.mark.gl

MODES = (("auto", "cpu"), ("zfail", "cpu"), ("auto", "gpu"), ("zfail", "gpu"))


@settings(profile(), max_examples=25 if PROFILE == "ci" else 600)
@given(scene=area_light_scenes())
def test_rasterizer_counts_match_the_witness(ctx, scene):
    witness = count_witness(scene, lost=0.0, skip=gl_vertex_ties(scene))
    with Renderer(scene, ctx) as renderer:
        for method, silhouettes in MODES:
            count = renderer.render(method, silhouettes, outputs=("lit",)).lit_count
            check_lit_count(scene, count, f"raster-{method}-{silhouettes}", 0.0, witness)
