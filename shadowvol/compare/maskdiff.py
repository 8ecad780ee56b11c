"""Comparing two sets of shadow masks pixel by pixel: the one definition of a mask edge, the
mismatch counts (in total and away from edges), the IoU of the shadow regions, and the
difference picture.  Used by the `compare` command and by the mask tests' budget
(tests/conftest.py), so both judge masks the same way.

Masks are as CONVENTIONS.md defines them: lit (L, H, W) bool, coverage (H, W) bool.  "got" is the
renderer under test (the rasterizer), "ref" the reference (the ray tracer).
"""

from __future__ import annotations

import numpy as np

# The difference picture's colours, (3,) uint8 RGB each.
BOTH_LIT = (255, 255, 255)
BOTH_SHADOWED = (96, 96, 96)
UNCOVERED = (0, 0, 0)                   # neither renderer sees geometry here
SHADOWED_ONLY_IN_GOT = (230, 30, 30)    # red: the raster shadows a pixel the reference lights
SHADOWED_ONLY_IN_REF = (40, 80, 255)    # blue: the reference shadows a pixel the raster lights
COVERAGE_DIFFERS = (255, 220, 0)        # yellow: geometry in one renderer only

LEGEND = (("both lit", BOTH_LIT), ("both shadowed", BOTH_SHADOWED),
          ("shadowed only in the raster", SHADOWED_ONLY_IN_GOT),
          ("shadowed only in the ray tracer", SHADOWED_ONLY_IN_REF),
          ("uncovered", UNCOVERED), ("coverage differs", COVERAGE_DIFFERS))


def edge_pixels(mask: np.ndarray) -> np.ndarray:
    """(H, W) bool: pixels whose 3x3 neighbourhood in `mask` (H, W) bool is not uniform (the
    image border repeats its edge pixels, so it is no edge by itself)."""
    m = np.pad(np.asarray(mask, dtype=bool), 1, mode="edge")
    h, w = mask.shape
    windows = [m[dy:dy + h, dx:dx + w] for dy in range(3) for dx in range(3)]
    return np.logical_or.reduce(windows) & ~np.logical_and.reduce(windows)


def near_edges(got_lit: np.ndarray, got_cov: np.ndarray, ref_lit: np.ndarray,
               ref_cov: np.ndarray) -> np.ndarray:
    """(H, W) bool: pixels within one pixel of an edge of either renderer's lit mask
    (got_lit, ref_lit: (H, W) bool, one light) or coverage mask (H, W) bool."""
    return (edge_pixels(got_cov) | edge_pixels(ref_cov) |
            edge_pixels(got_lit) | edge_pixels(ref_lit))


def mask_report(got_lit, got_cov, ref_lit, ref_cov) -> list[dict]:
    """Per light (and one entry for coverage, first): mismatched pixels in total and in the
    interior (farther than one pixel from an edge of the lit or coverage mask in either image).

    got_lit, ref_lit : (L, H, W) bool;  got_cov, ref_cov : (H, W) bool.
    Returns [{"what": "coverage" | "light i", "total": int, "interior": int}, ...], L + 1 rows.
    """
    near_cov = edge_pixels(ref_cov) | edge_pixels(got_cov)
    rows = [{"what": "coverage", "total": int((got_cov != ref_cov).sum()),
             "interior": int(((got_cov != ref_cov) & ~near_cov).sum())}]
    for i in range(len(ref_lit)):
        near = near_cov | edge_pixels(ref_lit[i]) | edge_pixels(got_lit[i])
        bad = got_lit[i] != ref_lit[i]
        rows.append({"what": f"light {i}", "total": int(bad.sum()),
                     "interior": int((bad & ~near).sum())})
    return rows


def shadow_iou(got_lit, got_cov, ref_lit, ref_cov) -> float:
    """Intersection over union of the shadow regions (shadow = covered & ~lit) of one light:
    got_lit, ref_lit, got_cov, ref_cov (H, W) bool.  1.0 when neither has any shadow (they
    agree perfectly)."""
    a = got_cov & ~got_lit
    b = ref_cov & ~ref_lit
    union = int((a | b).sum())
    return 1.0 if union == 0 else int((a & b).sum()) / union


def light_stats(got_lit, got_cov, ref_lit, ref_cov) -> dict:
    """The numbers of one light (all arguments (H, W) bool):

    mismatched : int, pixels where the lit masks differ
    interior   : int, of those, the ones farther than one pixel from an edge (`near_edges`)
    iou        : float, `shadow_iou`
    """
    bad = got_lit != ref_lit
    return {"mismatched": int(bad.sum()),
            "interior": int((bad & ~near_edges(got_lit, got_cov, ref_lit, ref_cov)).sum()),
            "iou": shadow_iou(got_lit, got_cov, ref_lit, ref_cov)}


def diff_panel(got_lit, got_cov, ref_lit, ref_cov) -> np.ndarray:
    """(H, W, 3) uint8: the difference of one light's masks ((H, W) bool each) in the colours
    above — both lit, both shadowed, shadowed only in got (red), only in ref (blue), uncovered
    in both (black), covered in one only (yellow)."""
    p = np.zeros(got_lit.shape + (3,), np.uint8)
    p[:] = UNCOVERED
    p[ref_cov & got_cov] = BOTH_SHADOWED
    p[got_lit & ref_lit] = BOTH_LIT
    p[~got_lit & ref_lit] = SHADOWED_ONLY_IN_GOT
    p[got_lit & ~ref_lit] = SHADOWED_ONLY_IN_REF
    p[got_cov != ref_cov] = COVERAGE_DIFFERS
    return p


def diff_image(got_lit, got_cov, ref_lit, ref_cov) -> np.ndarray:
    """(H, L*W, 3) uint8: `diff_panel` of every light side by side (lit (L, H, W) bool,
    coverage (H, W) bool); (1, 1, 3) black when there are no lights."""
    panels = [diff_panel(g, got_cov, r, ref_cov) for g, r in zip(got_lit, ref_lit)]
    return np.concatenate(panels, axis=1) if panels else np.zeros((1, 1, 3), np.uint8)


# ---- per-sample counts of area lights ----------------------------------------------------------

def count_edges(count: np.ndarray) -> np.ndarray:
    """(H, W) bool: pixels whose 3x3 neighbourhood in `count` (H, W) int is not uniform.  Each
    lies on an edge of some sample's hard mask (were every sample's mask uniform there, so
    would be their sum): the edges a renderer's per-sample masks show through its count."""
    c = np.pad(np.asarray(count), 1, mode="edge")
    h, w = count.shape
    windows = [c[dy:dy + h, dx:dx + w] for dy in range(3) for dx in range(3)]
    return np.logical_or.reduce([win != count for win in windows])


def count_stats(got_count, got_cov, ref_count, ref_cov, ref_sample_edges) -> dict:
    """The count numbers of one area light (lit_count (H, W) uint16 each, coverage (H, W) bool,
    `ref_sample_edges` (H, W) bool: pixels on an edge of some sample's reference hard mask):

    counts_differ    : int, pixels whose counts differ
    counts_interior  : int, of those, the ones on no edge of a sample's hard mask in either
                       renderer (`ref_sample_edges`, `count_edges` of got) nor of the coverage
    counts_largest   : int, the largest |difference| of the counts
    """
    differ = got_count != ref_count
    near = (edge_pixels(got_cov) | edge_pixels(ref_cov) | ref_sample_edges |
            count_edges(got_count))
    return {"counts_differ": int(differ.sum()), "counts_interior": int((differ & ~near).sum()),
            "counts_largest": int(np.abs(got_count.astype(np.int64) - ref_count).max(initial=0))}


def visibility_panel(count: np.ndarray, samples: int, coverage: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8: count / samples as grey (white: every sample reaches the pixel), the
    uncovered pixels black."""
    v = np.round(np.asarray(count, np.float64) / samples * 255).astype(np.uint8)
    panel = np.repeat(v[..., None], 3, axis=2)
    panel[~coverage] = UNCOVERED
    return panel


def count_diff_panel(got_count, ref_count, coverage) -> np.ndarray:
    """(H, W, 3) uint8: where the counts differ, red (got higher) or blue (ref higher), the
    brighter the larger the difference; equal counts dark grey, uncovered black."""
    d = got_count.astype(np.int64) - ref_count
    panel = np.zeros(d.shape + (3,), np.uint8)
    panel[coverage] = (40, 40, 40)
    level = np.clip(128 + np.abs(d) * 16, 0, 255).astype(np.uint8)
    panel[d > 0] = np.stack([level, np.zeros_like(level), np.zeros_like(level)], -1)[d > 0]
    panel[d < 0] = np.stack([np.zeros_like(level), np.zeros_like(level) + 60, level], -1)[d < 0]
    return panel
