"""The float64 brute-force judge of the reference masks (tests only; imported by the tests
that use it, as strategies.py is; tests/ is on sys.path).

`exact_masks` is the definition of CONVENTIONS.md's "lit" written as plainly as possible: for
every pixel centre, the nearest triangle along the float64 ray (every triangle tried, no BVH),
then for every light the segment from that point to the light tested against every other
triangle (Möller–Trumbore in float64, the visible triangle skipped, nothing moved off the
segment).  It is slow (pixels x triangles), so it runs on small scenes and crops.

`exact_casters` is the same walk for the ground truth: every sample of every light (an area
light's samples as hard lights), and per object whether it meets the segment.
`exact_ties` adds where the brute force itself is within its error bound of the other answer;
`exact_sample_masks` and `count_report` are the soft-shadow witness (CONVENTIONS.md, "Area
lights"), `check_counts` its verdict on any renderer's lit_count.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from builders import TEST_OUTPUT
from hypothesis import note

import raytrace
from raytrace.camera import pixel_focal, primary_rays
from raytrace.tolerances import LIFT_HEIGHTS, frame_origin, light_margin, shadow_height
from shadowvol.compare.maskdiff import diff_image, edge_pixels, mask_report
from shadowvol.io import save_png
from shadowvol.pictures import masks_image
from shadowvol.scenefile import save_scene
from shadowvol.frame import caster_words
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
    H, W = scene.height, scene.width
    pix = np.arange(H * W).reshape(H, W)[rows, cols]
    shape = pix.shape
    tri, first, covered, p, n = _primary(scene, pix.reshape(-1))
    casts, receives = _switches(scene, first)
    lit = np.zeros((len(scene.lights), len(first)), bool)
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
        lit[i] = ok   # blocked below, where the light and the pixel's object take shadows
        for c in _chunks(len(idx), len(tri)):
            k = idx[c]
            k = k[ok[k] & receives[k] & light.shadows]
            if len(k) == 0:
                continue
            t = _ray_triangles(p[k], np.ascontiguousarray(seg[k]), tri)
            t[np.arange(len(k)), first[k]] = np.inf  # skip only the visible triangle
            t[:, ~casts] = np.inf  # an object that casts no shadow blocks nothing
            blocked = ((t > EXACT_T_MIN) & (t < t_max)).any(axis=1)
            lit[i, k] = ~blocked
    return lit.reshape((-1,) + shape), covered.reshape(shape)


# The brute force's own error bound, relative to the distances from the eye of the point and
# of the triangle's corners (float32 rounds both in the eye's frame; Embree's edge tests work
# on corners minus the ray's origin): a pixel or a shadow segment that passes within it of a
# triangle's edge, two hits within it of each other,
# or n·l̂ within TIE_COSINE of 0 (a spot: the cone's cosine within it) is a tie, which float32
# (Embree's rays, the frame's rounding, 2**-24 relative) may decide either way.  100 times
# what float32 can move.
TIE_RELATIVE = 1e-5
TIE_COSINE = 1e-9


def _edge_distances(o: np.ndarray, d: np.ndarray, tri: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """t (P, M) where rays o + t·d (P, 3) meet the planes of triangles tri (M, 3, 3) (nan for
    a parallel ray) and the signed distance (P, M) of that point from the triangle's boundary
    in its plane (> 0 inside), float64."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    n = np.cross(b - a, c - a)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (np.einsum("mk,mk->m", n, a)[None] - o @ n.T) / (d @ n.T)
        q = o[:, None, :] + t[..., None] * d[:, None, :]
        side = []
        for p0, p1 in ((a, b), (b, c), (c, a)):
            e = p1 - p0
            inward = np.cross(n, e)
            inward /= np.linalg.norm(inward, axis=1, keepdims=True)
            side.append(np.einsum("pmk,mk->pm", q - p0[None], inward))
    return t, np.minimum.reduce(side)


def exact_ties(scene: Scene, lost: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`exact_masks` of the whole image with the brute force's ties: lit (L, H, W),
    coverage (H, W) and tie (L, H, W) bool, where the answer is within the brute force's error
    bound (TIE_RELATIVE, TIE_COSINE) of the other one: the pixel's ray within it of an edge or
    of a second surface; the facing or cone test within TIE_COSINE; the segment within it of
    an edge of a triangle it meets or misses, of a triangle through p (its plane within
    `lost` of p), or meeting a triangle within `lost` (world units) of p or of the light."""
    lit, cov = exact_masks(scene)
    with np.errstate(divide="ignore", invalid="ignore"):
        return (lit, cov) + (_ties(scene, lost),)


def _ties(scene: Scene, lost: float) -> np.ndarray:
    """The tie (L, H, W) bool of `exact_ties`."""
    vertices, faces, _ = scene.triangles()
    tri = vertices[faces]
    H, W = scene.height, scene.width
    o, d = primary_rays(scene.camera, W, H, unit=True)
    eye = scene.camera.eye
    reach = np.linalg.norm(tri - eye, axis=2).max(axis=1)  # (M,) corners from the eye
    tie = np.zeros((len(scene.lights), H * W), bool)
    for c in _chunks(len(o), 8 * len(tri)):
        t, edge = _edge_distances(o[c], d[c], tri)
        t = np.where(np.isfinite(t) & (t > 0), t, np.inf)
        front = np.where(edge >= 0, t, np.inf)
        k = np.argmin(front, axis=1)
        best = front[np.arange(len(k)), k]
        bound = TIE_RELATIVE * np.where(np.isfinite(best), best + np.linalg.norm(o[c] - eye,
                                                                                   axis=1), 1.0)
        pair = bound[:, None] + TIE_RELATIVE * reach[None]
        # a triangle in front (or just behind) that the ray misses or hits by less than that
        close = (np.abs(edge) <= pair) & (t <= best[:, None] + pair)
        second = np.sort(front, axis=1)[:, 1] if front.shape[1] > 1 else np.full(len(k), np.inf)
        primary_tie = close.any(axis=1) | (second - best <= bound)
        tie[:, c] |= primary_tie[None]
        hit = np.flatnonzero(np.isfinite(best))
        if len(hit):
            p = o[c][hit] + best[hit, None] * d[c][hit]
            tie[:, np.arange(c.start, c.stop)[hit]] |= _segment_ties(
                scene, tri, p, k[hit], d[c][hit], pair[hit], lost)
    return tie.reshape((len(scene.lights), H, W))


def _segment_ties(scene: Scene, tri: np.ndarray, p: np.ndarray, k: np.ndarray,
                  view: np.ndarray, bound: np.ndarray, lost: float) -> np.ndarray:
    """(L, h) bool: the shadow segments of points p (h, 3) on triangles k (h,) whose brute-force
    answer is a tie (see `exact_ties`); view (h, 3) the pixels' unit rays, bound (h, M) the
    error bound of p against each triangle."""
    n = np.cross(tri[k, 1] - tri[k, 0], tri[k, 2] - tri[k, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    n *= np.where(np.einsum("ij,ij->i", n, view) > 0, -1.0, 1.0)[:, None]
    out = np.zeros((len(scene.lights), len(p)), bool)
    for i, light in enumerate(scene.lights):
        if isinstance(light, DirectionalLight):
            seg = np.broadcast_to(-light.direction / np.linalg.norm(light.direction), p.shape)
            length = np.full(len(p), np.inf)
        else:
            seg = light.position - p
            length = np.linalg.norm(seg, axis=1)
            seg = seg / np.where(length > 0, length, 1.0)[:, None]
        cos = np.einsum("ij,ij->i", n, seg)
        out[i] = np.abs(cos) <= TIE_COSINE
        if isinstance(light, SpotLight):
            out[i] |= np.abs(-seg @ light.direction - light.cos_cutoff) <= TIE_COSINE
        t, edge = _edge_distances(p, np.ascontiguousarray(seg), tri)
        t[np.arange(len(p)), k] = np.nan  # p's own triangle never counts
        on = np.isfinite(t) & (t > -bound) & (t < length[:, None] + bound)
        near_edge = on & (np.abs(edge) <= bound)
        meets = on & (edge >= 0)
        at_ends = meets & ((t <= lost + bound) | (t >= length[:, None] - lost - bound))
        planes = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        planes /= np.linalg.norm(planes, axis=1, keepdims=True)
        through = np.abs(np.einsum("pk,mk->pm", p, planes) -
                         np.einsum("mk,mk->m", tri[:, 0], planes)[None]) <= lost + bound
        through[np.arange(len(p)), k] = False
        out[i] |= (near_edge | at_ends | (through & meets)).any(axis=1)
    return out


def lost_bound(scene) -> float:
    """An upper bound (world units) of what the ray tracer's margins may drop (the `lost` of
    `exact_ties`): LIFT_HEIGHTS heights at the largest weight any point of the scene can have,
    or the largest light margin (area lights: their samples')."""
    vertices, _, _ = scene.triangles()
    reach = float(np.abs(vertices - frame_origin(scene)).max())
    weight = 2.0 * np.sqrt(3.0) * reach
    margins = [float(light_margin(lt.position - frame_origin(scene), 2 * reach, weight))
               for light in scene.lights for lt in hard_lights(light)
               if hasattr(lt, "position")]
    return max([LIFT_HEIGHTS * float(shadow_height(weight))] + margins)


def exact_sample_masks(scene: Scene, light_index: int, rows: slice = slice(None),
                       cols: slice = slice(None)) -> np.ndarray:
    """The soft-shadow witness: (N, h, w) bool, `exact_masks` of each of light
    `light_index`'s samples (`hard_lights`) judged as a hard light; its sum is the count."""
    lit, _ = exact_masks(scene.replace(lights=hard_lights(scene.lights[light_index])), rows,
                         cols)
    return lit


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


def _switches(scene: Scene, first: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The shadow switches (CONVENTIONS.md, "Shadow switches") as plainly as possible: casts
    (M,) bool, each triangle's object casts shadows; receives (P,) bool, the object the pixel
    sees (`first` (P,), −1: none) receives them."""
    _, _, owner = scene.triangles()
    casts = np.array([o.cast_shadows for o in scene.objects], bool)
    receives = np.array([o.receive_shadows for o in scene.objects], bool)
    return casts[owner], receives[owner[np.maximum(first, 0)]]


def _primary(scene: Scene, pixels: np.ndarray | None = None):
    """The nearest triangle in float64 of `pixels` (flat indices, default every pixel): tri
    (M, 3, 3), first (P,) (−1: nothing), covered (P,), p (P, 3) the hit points, n (P, 3) their
    normals turned toward the camera."""
    vertices, faces, _ = scene.triangles()
    tri = vertices[faces]
    o, d = primary_rays(scene.camera, scene.width, scene.height, unit=False)
    if pixels is not None:
        o, d = o[pixels], d[pixels]
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
    casts, receives = _switches(scene, first)
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
            lit_count[i] += ok & ~(receives & sample.shadows)   # nothing blocks these
            idx = np.flatnonzero(ok & receives & sample.shadows)
            for c in _chunks(len(idx), len(tri)):
                k = idx[c]
                t = _ray_triangles(p[k], np.ascontiguousarray(seg[k]), tri)
                t[np.arange(len(k)), first[k]] = np.inf
                t[:, ~casts] = np.inf
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


def _windows(mask: np.ndarray) -> list[np.ndarray]:
    """The 9 shifts of (..., H, W) `mask` over its 3x3 neighbourhoods (the border repeated)."""
    pad = [(0, 0)] * (mask.ndim - 2) + [(1, 1), (1, 1)]
    m = np.pad(mask, pad, mode="edge")
    h, w = mask.shape[-2:]
    return [m[..., dy:dy + h, dx:dx + w] for dy in range(3) for dx in range(3)]


def count_bracket(samples: np.ndarray, coverage: np.ndarray, tie: np.ndarray | None = None
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The conventions' rule for counts, from the witness's per-sample masks samples (N, H, W)
    bool and coverage (H, W): (low, high, free), each (H, W).  low/high: the counts that
    moving every sample's hard edge by one pixel allows (per sample the least/most of its
    3x3 neighbourhood, summed); free: within one pixel of some sample's hard edge or of the
    coverage edge, where a count may differ from the witness's (inside the bracket).  tie
    (N, H, W) bool, optional: the samples whose brute-force answer is a tie there
    (`exact_ties`), which may go either way."""
    shifted = _windows(samples)
    low, high = np.logical_and.reduce(shifted), np.logical_or.reduce(shifted)
    if tie is not None:
        low, high = low & ~tie, high | tie
    low, high = low.sum(axis=0), high.sum(axis=0)
    free = edge_pixels(coverage) | (high != low)
    return low, high, free


def count_witness(scene: Scene, rows: slice = slice(None), cols: slice = slice(None),
                  lost: float | None = None, skip: np.ndarray | None = None) -> list[dict]:
    """Per light, the float64 witness of `count_report`: {"exact", "low", "high", "free",
    "samples", "coverage"}, computed once for any number of renderers' counts.  skip (H, W)
    bool, optional: pixels out of the check (`gl_vertex_ties`: the rasterizer's)."""
    coverage = exact_masks(scene.replace(lights=()), rows, cols)[1]
    out = []
    for i in range(len(scene.lights)):
        samples = exact_sample_masks(scene, i, rows, cols)
        tie = None if lost is None else exact_ties(
            scene.replace(lights=hard_lights(scene.lights[i])), lost)[2]
        low, high, free = count_bracket(samples, coverage, tie)
        if skip is not None:
            low, high, free = np.where(skip, 0, low), np.where(skip, len(samples), high), \
                free | skip
        out.append({"exact": samples.sum(axis=0), "low": low, "high": high, "free": free,
                    "samples": len(samples), "coverage": coverage})
    return out


def count_report(scene: Scene, lit_count: np.ndarray, rows: slice = slice(None),
                 cols: slice = slice(None), lost: float | None = None,
                 witness: list[dict] | None = None) -> list[dict]:
    """Per light, a renderer's lit_count (L, H, W) of `scene` against the float64 witness
    (`exact_sample_masks`): {"what", "interior": differences where no sample's hard edge lies
    within one pixel, "outside": counts outside `count_bracket`, "total", "count", "exact",
    "coverage"} (the last three arrays, for pictures).  lost: the renderer's own margin
    (`exact_ties`); given, the samples' ties (whole image only) may go either way.  witness:
    `count_witness`'s, when already computed."""
    got = np.asarray(lit_count, np.int64)[:, rows, cols]
    witness = witness if witness is not None else count_witness(scene, rows, cols, lost)
    report = []
    for i, w in enumerate(witness):
        report.append({"what": f"light {i}",
                       "interior": int(((got[i] != w["exact"]) & ~w["free"]).sum()),
                       "outside": int(((got[i] < w["low"]) | (got[i] > w["high"])).sum()),
                       "total": int((got[i] != w["exact"]).sum()), "count": got[i],
                       "exact": w["exact"], "samples": w["samples"], "coverage": w["coverage"]})
    return report


def gl_vertex_ties(scene: Scene, precision: float = 1 / 64) -> np.ndarray:
    """(H, W) bool: the pixels whose visible surface is a tie below GL's vertex precision
    (docs/CONVENTIONS.md): the pixel-centre ray passes within `precision` of a pixel of the
    edge of a triangle at or in front of the surface it hits, measured as the angle from
    the plane through the eye and the edge, against the pixel's angular size on the axis."""
    vertices, faces, _ = scene.triangles()
    tri = vertices[faces]
    H, W = scene.height, scene.width
    o, d = primary_rays(scene.camera, W, H, unit=True)
    eye = np.asarray(scene.camera.eye, np.float64)
    fx, fy, _, _ = pixel_focal(scene.camera, W, H)
    pixel = 1.0 / min(fx, fy)   # the larger side of a pixel, at unit depth
    out = np.zeros(H * W, bool)
    rel = tri - eye
    normals = [np.cross(rel[:, i], rel[:, (i + 1) % 3]) for i in range(3)]
    normals = [n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
               for n in normals]
    for c in _chunks(len(o), 8 * len(tri)):
        t, edge = _edge_distances(o[c], d[c], tri)
        t = np.where(np.isfinite(t) & (t > 0), t, np.inf)
        best = np.where(edge >= 0, t, np.inf).min(axis=1)
        at_or_front = t <= best[:, None] * (1 + 1e-6)
        near = np.zeros(t.shape, bool)
        for i, n in enumerate(normals):
            a, b = rel[:, i], rel[:, (i + 1) % 3]
            # the ray's angle from the edge's plane, and whether it passes between its ends
            angle = np.abs(d[c] @ n.T)
            between = (np.einsum("pk,mk->pm", d[c], np.cross(n, a)) >= 0) & \
                (np.einsum("pk,mk->pm", d[c], np.cross(b, n)) >= 0)
            near |= (angle <= precision * pixel) & between
        out[c] = (near & at_or_front & np.isfinite(t)).any(axis=1)
    return out.reshape(H, W)


def check_counts(request, scene: Scene, lit_count: np.ndarray, label: str = "",
                 rows: slice = slice(None), cols: slice = slice(None)) -> list[dict]:
    """The soft-shadow witness's verdict on a renderer's lit_count (L, H, W) of `scene` (any
    renderer: the ray tracer's `lit_count` here, the rasterizer's at the merge): equal to the
    float64 brute force (`exact_sample_masks`) at every pixel where no sample's hard edge lies within
    one pixel, and nowhere outside `count_bracket` (`count_report`).  On failure writes
    count/exact pictures under test-output/<test>/."""
    report = count_report(scene, lit_count, rows, cols)
    summary = [{k: r[k] for k in ("what", "interior", "outside", "total")} for r in report]
    if not any(r["interior"] or r["outside"] for r in report):
        return summary
    out = TEST_OUTPUT / re.sub(r"[^A-Za-z0-9_.-]+", "_", request.node.name + label)
    for i, r in enumerate(report):
        got, want, cov = r["count"][None] == r["samples"], r["exact"][None] == r["samples"], \
            r["coverage"]
        save_png(out / f"count_{i}.png", masks_image(got, cov))
        save_png(out / f"exact_{i}.png", masks_image(want, cov))
        save_png(out / f"diff_{i}.png", diff_image(got, cov, want, cov))
    pytest.fail(f"lit_count vs the float64 witness{label}: {summary}; budget: 0 interior, "
                f"0 outside the one-pixel bracket; pictures in {out}")


def check_lit_count(scene, lit_count, who: str, lost: float,
                    witness: list[dict] | None = None) -> None:
    """Raise AssertionError (hypothesis shrinks it) where `who`'s lit_count (L, H, W) breaks
    the rule, a sample whose brute-force answer is a tie (within `lost`, the renderer's
    margin, or the brute force's own bound: `exact_ties`) going either way; the scene is saved
    first.  witness: `count_witness(scene, lost=lost, ...)`, when already computed."""
    summary = [{k: r[k] for k in ("what", "interior", "outside", "total")}
               for r in count_report(scene, lit_count, lost=lost, witness=witness)]
    note(f"{who}: {summary}")
    if any(r["interior"] or r["outside"] for r in summary):
        path = TEST_OUTPUT / "soft-witness" / f"failing-{who}.json"
        save_scene(scene, path)  # overwritten while shrinking: the last one is the smallest
        raise AssertionError(f"{who} vs the float64 witness: {summary}; saved as {path}")
