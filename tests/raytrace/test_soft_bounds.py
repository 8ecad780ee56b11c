"""Property: the ray tracer's sampled soft shadows (`raytrace.soft_masks`' lit_count) against
the exact visibility (`raytrace.exact_soft`), within the bound the documented stratified layout
allows (tests/stratabound.py derives it for rect, polygon and disk lights; docs/CONVENTIONS.md,
"Area lights: exact visibility"), on random area-light scenes: closed, open and non-manifold
casters, a contact shadow, lights partly below the floor's plane, the whole 1e4 from the
origin.  The mean error over the penumbra falls as N grows 16 -> 64 -> 256 -> 1024 (the slope
printed).  Each sample lies in its own stratum (the bound's premise; a layout off by half a
stratum breaks it); a count off by one breaks the bound where the light is wholly seen or
hidden.  The rasterizer's counts: tests/raster/test_soft_bounds_raster.py.
HYPOTHESIS_PROFILE=long for the long run.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from stratabound import SHAPES, bound_scene, bound_scenes, check_within_bound, \
    inverse_concentric, layout, mean_errors
from strategies import PROFILE, profile

from raytrace.soft import soft_masks
from shadowvol import arealights
from shadowvol.planes import default_plane_axes

pytest.importorskip("shapely", reason="exact visibility needs shapely: "
                                      "pip install 'shadowvol[exact]'")

@settings(profile(), max_examples=12 if PROFILE == "ci" else 400)
@given(scene=bound_scenes())
def test_ray_tracer_counts_within_the_layout_bound(scene):
    check_within_bound(scene, soft_masks(scene).lit_count[0].astype(np.float64), "raytrace")


@pytest.mark.parametrize("kind", SHAPES)
def test_every_case_has_a_penumbra(kind):
    """The scenes have what the property is about: a penumbra crossed by the outline, with
    the light partly below the floor, and 1e4 from the origin."""
    for behind in (False, True):
        scene = bound_scene(kind, 16, 1, behind=behind, far=True)
        assert check_within_bound(scene, soft_masks(scene).lit_count[0].astype(float),
                                  "raytrace") > 30


@pytest.mark.parametrize("kind", SHAPES)
def test_mean_error_falls_with_n(kind, capsys):
    """16 -> 64 -> 256 -> 1024 samples: the mean |lit_count / N - V| over the penumbra falls
    at each step, as N^-0.75 along an edge for a stratified grid; the fitted slope printed
    and steeper than N^-1/2 (independent samples' rate)."""
    means, slope = mean_errors(kind, lambda scene: soft_masks(scene).lit_count[0])
    with capsys.disabled():
        print(f"\nraytrace {kind}: mean |lit_count/N - V| {[f'{m:.4f}' for m in means]}, "
              f"slope {slope:.2f} per log N")
    assert all(b < a for a, b in zip(means, means[1:])), means
    assert slope < -0.5, slope


def strata(light) -> np.ndarray:
    """(N, 2) int: the (i, j) cell of the unit square each of `light`'s samples comes from,
    by the inverse of its shape's map."""
    nu, nv = layout(light)
    u, v = default_plane_axes(light.normal)
    flat = (light.positions - light.center) @ np.stack([u, v], axis=1)
    if light.shape == "rect":
        uv = flat / light.size + 0.5
    elif light.shape == "disk":
        uv = inverse_concentric(flat, light.radius)
    else:
        uv = _inverse_polygon(light, flat, u, v)
    return np.floor(uv * [nu, nv]).astype(np.int64)


def _inverse_polygon(light, flat, u, v) -> np.ndarray:
    outline = (light.vertices - light.center) @ np.stack([u, v], axis=1)
    tris = outline[arealights.triangulate(outline)]
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    area = np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    edges = np.concatenate([[0.0], np.cumsum(area) / area.sum()])
    out = np.full((len(flat), 2), np.nan)
    for k in range(len(tris)):
        m = np.array([b[k] - a[k], c[k] - a[k]]).T
        lb, lc = np.linalg.solve(m, (flat - a[k]).T)
        inside = (lb >= -1e-12) & (lc >= -1e-12) & (lb + lc <= 1 + 1e-12)
        root = lb + lc
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(root > 0, lc / root, 0.0)
        uk = edges[k] + root ** 2 * (edges[k + 1] - edges[k])
        take = inside & np.isnan(out[:, 0])
        out[take] = np.column_stack([uk, t])[take]
    return out


@pytest.mark.parametrize("kind", SHAPES)
def test_each_sample_lies_in_its_stratum(kind):
    """The bound's premise: sample k of an nu x nv layout lies in the image of cell
    (k mod nu, k div nu), for each shape's map (a layout off by half a stratum fails)."""
    for n in (16, 64, 256):
        light = bound_scene(kind, n, 2).lights[0]
        nu, _ = layout(light)
        k = np.arange(n)
        want = np.column_stack([k % nu, k // nu])
        assert (strata(light) == want).all(), kind


def test_a_count_off_by_one_is_caught():
    """The planted error: every count one short where any sample is counted (a sample
    dropped) breaks the bound where the light is wholly seen (bound 0 there)."""
    scene = bound_scene("rect", 64, 3)
    counts = soft_masks(scene).lit_count[0].astype(float)
    with pytest.raises(AssertionError, match="past the bound"):
        check_within_bound(scene, np.maximum(counts - 1, 0), "planted")


def test_a_layout_off_by_half_a_stratum_is_caught(monkeypatch):
    """The planted error: the stratified pattern shifted by half a cell along u (wrapped):
    the counts still look plausible, but no sample lies in its documented stratum."""
    original = arealights.unit_square

    def shifted(n, pattern, seed, grid=None):
        nu = (grid or arealights.grid_shape(n))[0]
        return (original(n, pattern, seed, grid) + [0.5 / nu, 0.0]) % 1.0

    monkeypatch.setattr(arealights, "unit_square", shifted)
    for kind in SHAPES:
        with pytest.raises(AssertionError):
            test_each_sample_lies_in_its_stratum(kind)
