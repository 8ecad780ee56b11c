"""The float64 brute-force judge of the reference masks (tests only; imported by the tests
that use it, as strategies.py is; tests/ is on sys.path).

`exact_masks` is the definition of CONVENTIONS.md's "lit" written as plainly as possible: for
every pixel centre, the nearest triangle along the float64 ray (every triangle tried, no BVH),
then for every light the segment from that point to the light tested against every other
triangle (Möller–Trumbore in float64, the visible triangle skipped, nothing moved off the
segment).  It is slow (pixels x triangles), so it runs on small scenes and crops.

`exact_casters` is the same walk for the ground truth: every sample of every light (an area
light's samples as hard lights), and per object whether it meets the segment.
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
from shadowvol.fields import caster_words
from shadowvol.scene import DirectionalLight, Scene, SpotLight, hard_lights

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


def _primary(scene: Scene):
    """Every pixel's nearest triangle in float64: tri (M, 3, 3), first (P,) (−1: nothing),
    covered (P,), p (P, 3) the hit points, n (P, 3) their normals turned toward the camera."""
    vertices, faces, _ = scene.triangles()
    tri = vertices[faces]
    o, d = primary_rays(scene.camera, scene.width, scene.height, unit=False)
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
    n *= np.where(np.einsum("ij,ij->i", n, d) > 0, -1.0, 1.0)[:, None]
    return tri, first, covered, p, n


def exact_casters(scene: Scene) -> dict[str, np.ndarray]:
    """The ground truth's counts and casters by brute force in float64: casters (L, H, W, K)
    uint64 (object j: bit j mod 64 of word j div 64), lit_count and facing_count (L, H, W)
    uint16, object_id (H, W) uint16.  Per sample: facing is n·l > 0 and inside the sample's
    cone; object j casts when one of its triangles meets the segment (t in (EXACT_T_MIN,
    t_max), the visible triangle skipped), every triangle of every object tried."""
    tri, first, covered, p, n = _primary(scene)
    _, _, owner = scene.triangles()
    objects, L, P = len(scene.objects), len(scene.lights), len(p)
    starts = np.searchsorted(owner, np.arange(objects))   # each object's first triangle
    K = caster_words(objects)
    casters = np.zeros((L, P, K), np.uint64)
    lit_count = np.zeros((L, P), np.uint16)
    facing_count = np.zeros((L, P), np.uint16)
    for i, light in enumerate(scene.lights):
        for sample in hard_lights(light):
            if isinstance(sample, DirectionalLight):
                seg, t_max = np.broadcast_to(-sample.direction * scene.extent, p.shape), np.inf
            else:
                seg, t_max = sample.position - p, 1.0
            ok = covered & (np.einsum("ij,ij->i", n, seg) > 0)
            if isinstance(sample, SpotLight):
                away = -seg
                ok &= away @ sample.direction >= sample.cos_cutoff * np.linalg.norm(away, axis=1)
            facing_count[i] += ok
            idx = np.flatnonzero(ok)
            for c in _chunks(len(idx), len(tri)):
                k = idx[c]
                t = _ray_triangles(p[k], np.ascontiguousarray(seg[k]), tri)
                t[np.arange(len(k)), first[k]] = np.inf
                between = (t > EXACT_T_MIN) & (t < t_max)
                per_object = np.logical_or.reduceat(between, starts, axis=1)   # (k, objects)
                lit_count[i, k] += ~per_object.any(axis=1)
                padded = np.zeros((len(k), 64 * K), bool)
                padded[:, :objects] = per_object
                casters[i, k] |= np.packbits(padded, axis=1, bitorder="little").view("<u8")
    H, W = scene.height, scene.width
    ids = np.where(covered, owner[np.maximum(first, 0)] + 1, 0).astype(np.uint16)
    return {"casters": casters.reshape(L, H, W, K), "lit_count": lit_count.reshape(L, H, W),
            "facing_count": facing_count.reshape(L, H, W), "object_id": ids.reshape(H, W)}
