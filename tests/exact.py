"""The float64 brute-force judge of the reference masks (tests only; imported by the tests
that use it, as strategies.py is; tests/ is on sys.path).

`exact_masks` is the definition of CONVENTIONS.md's "lit" written as plainly as possible: for
every pixel centre, the nearest triangle along the float64 ray (every triangle tried, no BVH),
then for every light the segment from that point to the light tested against every other
triangle (Möller–Trumbore in float64, the visible triangle skipped, nothing moved off the
segment).  It is slow (pixels x triangles), so it runs on small scenes and crops.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from builders import TEST_OUTPUT

import raytrace
from raytrace.camera import primary_rays
from shadowvol.compare.maskdiff import diff_image, mask_report
from shadowvol.io import save_png
from shadowvol.pictures import masks_image
from shadowvol.scene import DirectionalLight, Scene, SpotLight

# The checker's own float64 tolerance: a triangle met at t <= EXACT_T_MIN of the segment (or,
# for a directional light, of the scene's extent) touches its start point and is not "between"
# (a coplanar overlapping triangle).  Nine orders below float32's resolution.
EXACT_T_MIN = 1e-12
EXACT_EDGE_BUDGET = 0.0005
PAIRS_PER_CHUNK = 1 << 18


def _ray_triangles(o: np.ndarray, d: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Möller–Trumbore, float64: t (P, M) of rays o (P, 3) + t·d (P, 3) against triangles
    tri (M, 3, 3), inf where a ray misses (edges inclusive, parallel rays miss)."""
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    pv = np.cross(d[:, None, :], e2[None])
    det = np.einsum("pmk,mk->pm", pv, e1)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        s = o[:, None, :] - tri[None, :, 0]
        u = np.einsum("pmk,pmk->pm", s, pv) * inv
        q = np.cross(s, e1[None])
        v = np.einsum("pk,pmk->pm", d, q) * inv
        t = np.einsum("mk,pmk->pm", e2, q) * inv
        ok = (det != 0) & (u >= 0) & (v >= 0) & (u + v <= 1)
    return np.where(ok, t, np.inf)


def _chunks(n: int, m: int):
    step = max(1, PAIRS_PER_CHUNK // max(m, 1))
    for a in range(0, n, step):
        yield slice(a, min(a + step, n))


def exact_masks(scene: Scene, rows: slice = slice(None), cols: slice = slice(None)
                ) -> tuple[np.ndarray, np.ndarray]:
    """lit (L, h, w) and coverage (h, w) of the pixel window (rows, cols), by brute force in
    float64 (see the module docstring)."""
    vertices, faces, _ = scene.triangles()
    tri = vertices[faces]
    H, W = scene.height, scene.width
    o, d = primary_rays(scene.camera, W, H, unit=False)
    pix = np.arange(H * W).reshape(H, W)[rows, cols]
    shape = pix.shape
    o, d = o[pix.reshape(-1)], d[pix.reshape(-1)]
    first = np.full(len(o), -1)
    t_hit = np.full(len(o), np.inf)
    for c in _chunks(len(o), len(tri)):
        t = _ray_triangles(o[c], d[c], tri)
        t[t <= 0] = np.inf
        first[c] = np.argmin(t, axis=1)
        t_hit[c] = t[np.arange(len(t)), first[c]]
    covered = np.isfinite(t_hit)
    first[~covered] = -1
    p = o + np.where(covered, t_hit, 0.0)[:, None] * d
    n = np.cross(tri[first, 1] - tri[first, 0], tri[first, 2] - tri[first, 0])
    n *= np.where(np.einsum("ij,ij->i", n, d) > 0, -1.0, 1.0)[:, None]  # toward the camera
    lit = np.zeros((len(scene.lights), len(o)), bool)
    idx = np.flatnonzero(covered)
    for i, light in enumerate(scene.lights):
        if isinstance(light, DirectionalLight):
            seg = np.broadcast_to(-light.direction * scene.extent, p.shape)  # t in units of it
            t_max = np.inf
        else:
            seg = light.position - p
            t_max = 1.0
        ok = covered & (np.einsum("ij,ij->i", n, seg) > 0)
        if isinstance(light, SpotLight):
            away = -seg
            ok &= away @ light.direction >= light.cos_cutoff * np.linalg.norm(away, axis=1)
        for c in _chunks(len(idx), len(tri)):
            k = idx[c]
            k = k[ok[k]]
            if len(k) == 0:
                continue
            t = _ray_triangles(p[k], np.ascontiguousarray(seg[k]), tri)
            t[np.arange(len(k)), first[k]] = np.inf  # skip only the visible triangle
            blocked = ((t > EXACT_T_MIN) & (t < t_max)).any(axis=1)
            lit[i, k] = ~blocked
    return lit.reshape((-1,) + shape), covered.reshape(shape)


def check_exact(request, scene: Scene, rows: slice = slice(None), cols: slice = slice(None),
                reference=None, budget: int | None = None) -> list[dict]:
    """Embree's masks (the window of them) against `exact_masks`: no interior mismatch, and at
    most `budget` mismatches per mask (default: EXACT_EDGE_BUDGET of the pixels, at least 4).
    On failure writes reference.png, exact.png and diff.png under test-output/<test>/."""
    lit, cov = reference if reference is not None else raytrace.shadow_masks(scene)
    lit, cov = lit[:, rows, cols], cov[rows, cols]
    ex_lit, ex_cov = exact_masks(scene, rows, cols)
    report = mask_report(lit, cov, ex_lit, ex_cov)
    interior = sum(r["interior"] for r in report)
    worst = max(r["total"] for r in report)
    if budget is None:
        budget = max(4, int(EXACT_EDGE_BUDGET * cov.size))
    if interior or worst > budget:
        out = TEST_OUTPUT / re.sub(r"[^A-Za-z0-9_.-]+", "_", request.node.name)
        save_png(out / "reference.png", masks_image(lit, cov))
        save_png(out / "exact.png", masks_image(ex_lit, ex_cov))
        save_png(out / "diff.png", diff_image(lit, cov, ex_lit, ex_cov))
        pytest.fail(f"reference vs exact float64: {report}; budget 0 interior, <= {budget} in "
                    f"all per mask; pictures in {out}")
    # the scene must test something: shadow and light both present somewhere
    assert ex_lit.any() and (ex_cov[None] & ~ex_lit).any()
    return report
