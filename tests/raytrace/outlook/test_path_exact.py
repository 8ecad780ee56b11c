"""The path tracer's direct light converges to the exact one.

The path tracer's next-event estimate of an area light sums the light's N samples (each
weighted by its cosine at the light, no fall-off: docs/CONVENTIONS.md, "Area lights"), so at
depth 1 on Lambertian surfaces a pixel is kd · color · intensity / N · the sum over visible
samples of cos(at p) cos(at the light).  Over independent jitters of the stratified layout
(the light's seed) that is an unbiased estimate of its limit kd · color · intensity · D, D the
exact cosine-weighted measure of the visible region (`exact_visibility(direct=True)`, drawn by
`raytrace render --integrator analytic`).  (`irradiance_exact` is the same region's measure
with the inverse-square fall-off, which the renderers' sampled shading does not have.)

A one-sample t-test over the seeds of the penumbra's mean difference: p >= 0.01, for rect,
polygon and disk lights; and sharp: the light 2% too bright gives p < 0.01.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from stratabound import bound_scene

from raytrace.exact_soft import exact_visibility
from raytrace.outlook import analytic
from raytrace.outlook.path.pathtrace import render

scipy_stats = pytest.importorskip("scipy.stats")
pytest.importorskip("shapely", reason="exact visibility needs shapely: "
                                      "pip install 'shadowvol[exact]'")

SEEDS = 24
P_MIN = 0.01


def _differences(kind: str, brighter: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """(SEEDS,) the penumbra's mean of path traced minus analytic (red channel) for each seed
    of the light's jitter, and the analytic penumbra's mean."""
    base = bound_scene(kind, 16, 7, casters=("closed", "open", "contact"), size=(32, 24))
    v = exact_visibility(base).visibility[0]
    penumbra = (v > 0.02) & (v < 0.98)
    assert penumbra.sum() > 25
    exact = analytic.render(base)[..., 0]
    out = []
    for seed in range(SEEDS):
        light = dataclasses.replace(base.lights[0], seed=seed,
                                    intensity=base.lights[0].intensity * brighter)
        scene = base.replace(lights=[light])
        traced = render(scene, spp=1, seed=seed, max_depth=1, jitter=False).image[..., 0]
        out.append(float((traced - exact)[penumbra].mean()))
    return np.array(out), float(exact[penumbra].mean())


@pytest.mark.parametrize("kind", ["rect", "polygon", "disk"])
def test_the_path_tracer_s_direct_light_converges_to_the_exact_one(kind, capsys):
    d, scale = _differences(kind)
    p = scipy_stats.ttest_1samp(d, 0.0).pvalue
    with capsys.disabled():
        print(f"\npath tracer vs exact ({kind}): mean difference {d.mean():.2e} "
              f"(std {d.std(ddof=1):.2e}, penumbra mean {scale:.3f}), p = {p:.3f}")
    assert p >= P_MIN, (d.mean(), p)
    assert np.abs(d).max() < 0.2 * scale       # each seed's estimate is already close


def test_a_light_two_percent_too_bright_is_caught():
    d, _ = _differences("rect", brighter=1.02)
    assert scipy_stats.ttest_1samp(d, 0.0).pvalue < P_MIN
