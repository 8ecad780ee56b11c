"""Property: for random scenes, the rasterizer's masks equal the ray tracer's away from edges.

Random scenes (tests/strategies.py): closed meshes, open and non-manifold soups, unwelded
vertices, reversed windings, cameras anywhere (inside objects and volumes, deep near planes),
1-3 point, directional and spot lights.  `shadowvol.render` with method auto and zfail (CPU
silhouettes, and both with GPU silhouettes) against
`raytrace.shadow_masks`: zero mismatches farther than one pixel from a mask edge
(shadowvol.compare.maskdiff).  A failing scene is shrunk by hypothesis and saved as a JSON scene file
(`save_scene`) under test-output/robustness/, which any command renders:

    shadowvol compare test-output/robustness/failing-auto.json -o diff.png

Profiles: HYPOTHESIS_PROFILE=ci (default, 50 scenes per test) or long (1500); see
strategies.py.
"""

from __future__ import annotations

import numpy as np
from builders import TEST_OUTPUT
from hypothesis import given, note, settings
from strategies import profile, scenes

import raytrace
from shadowvol.compare.maskdiff import mask_report
from shadowvol.raster.renderer import Renderer
from shadowvol.scenefile import load_scene, save_scene

OUT = TEST_OUTPUT / "robustness"
METHODS = ("auto", "zfail")


def check_scene(ctx, scene, method: str, silhouettes: str = "cpu") -> None:
    lit, cov = raytrace.shadow_masks(scene)
    with Renderer(scene, ctx) as r:
        res = r.render(method, silhouettes)
        masks = r.render(method, silhouettes, outputs=("lit", "coverage"))   # the mask pass
    # a mask-only frame has its own passes (passes.mask_pass): the same masks, bit for bit
    np.testing.assert_array_equal(masks.lit, res.lit)
    np.testing.assert_array_equal(masks.coverage, res.coverage)
    report = mask_report(res.lit, res.coverage, lit, cov)
    if silhouettes != "cpu":
        method = f"{method}-{silhouettes}"
    note(f"{method}: {report}")
    if any(row["interior"] for row in report):
        path = OUT / f"failing-{method}.json"
        save_scene(scene, path)  # overwritten while shrinking: the last one is the smallest
        raise AssertionError(
            f"{method}: interior mismatches {[(r['what'], r['interior']) for r in report]}; "
            f"the scene is saved as {path} (render it: shadowvol compare {path} -o diff.png)")


@profile()
@given(scene=scenes())
def test_random_scenes_auto(ctx, scene):
    check_scene(ctx, scene, "auto")


@profile()
@given(scene=scenes())
def test_random_scenes_zfail(ctx, scene):
    check_scene(ctx, scene, "zfail")


@profile()
@given(scene=scenes())
def test_random_scenes_gpu_silhouettes(ctx, scene):
    """The silhouettes found by the geometry shader (auto, and z-fail everywhere)."""
    check_scene(ctx, scene, "auto", "gpu")
    check_scene(ctx, scene, "zfail", "gpu")


@settings(profile(), max_examples=5)
@given(scene=scenes())
def test_a_saved_scene_reproduces_its_masks(ctx, tmp_path_factory, scene):
    """The failure file is a faithful copy: the same masks from both renderers."""
    path = tmp_path_factory.mktemp("saved") / "s.json"
    save_scene(scene, path)
    again = load_scene(path)
    for a, b in zip(raytrace.shadow_masks(scene), raytrace.shadow_masks(again)):
        np.testing.assert_array_equal(a, b)
    with Renderer(scene, ctx) as r1, Renderer(again, ctx) as r2:
        np.testing.assert_array_equal(r1.render().lit, r2.render().lit)
