"""Property: the rasterizer's sampled soft shadows (lit_count of `Renderer.render`, auto and
z-fail) against the exact visibility, within the bound the documented stratified layout allows
(tests/stratabound.py; docs/CONVENTIONS.md, "Area lights: exact visibility"), on the random
area-light scenes of tests/raytrace/test_soft_bounds.py (rect, polygon and disk lights; closed,
open and non-manifold casters, a contact shadow, lights partly below the floor's plane, 1e4
from the origin; CONVENTIONS' one-pixel rule for counts where a sample's hard edge lies
within a pixel, as tests/raster/test_soft_witness_raster.py has it); the mean error over the penumbra falls as N grows 16 -> 64 -> 256 -> 1024,
the slope printed.  HYPOTHESIS_PROFILE=long for the long run.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from stratabound import SHAPES, bound_scene, bound_scenes, check_within_bound, mean_errors
from strategies import PROFILE, profile

from shadowvol.raster.renderer import Renderer

pytestmark = pytest.mark.gl
pytest.importorskip("shapely", reason="exact visibility needs shapely: "
                                      "pip install 'shadowvol[exact]'")


def _counts(ctx, scene, method="auto"):
    with Renderer(scene, ctx) as renderer:
        return renderer.render(method, "cpu", outputs=("lit",)).lit_count[0].astype(np.float64)


@settings(profile(), max_examples=8 if PROFILE == "ci" else 300)
@given(scene=bound_scenes())
def test_rasterizer_counts_within_the_layout_bound(ctx, scene):
    for method in ("auto", "zfail"):
        check_within_bound(scene, _counts(ctx, scene, method), f"raster-{method}",
                           one_pixel=True)


@pytest.mark.parametrize("kind", SHAPES)
def test_every_case_has_a_penumbra(ctx, kind):
    for behind in (False, True):
        scene = bound_scene(kind, 16, 1, behind=behind, far=True)
        assert check_within_bound(scene, _counts(ctx, scene), "raster", one_pixel=True) > 30


@pytest.mark.parametrize("kind", SHAPES if PROFILE == "long" else ("rect",))
def test_mean_error_falls_with_n(ctx, kind, capsys):
    """As the ray tracer's (1,024 shadow-volume passes per scene: the rect alone under the ci
    profile, every shape under long)."""
    means, slope = mean_errors(kind, lambda scene: _counts(ctx, scene))
    with capsys.disabled():
        print(f"\nraster {kind}: mean |lit_count/N - V| {[f'{m:.4f}' for m in means]}, "
              f"slope {slope:.2f} per log N")
    assert all(b < a for a, b in zip(means, means[1:])), means
    assert slope < -0.5, slope


def test_a_count_off_by_one_is_caught(ctx):
    scene = bound_scene("disk", 64, 3)
    with pytest.raises(AssertionError, match="past the bound"):
        check_within_bound(scene, _counts(ctx, scene) + 1, "planted", one_pixel=True)
