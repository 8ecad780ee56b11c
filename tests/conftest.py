"""Shared fixtures: the one GL context of the session, and the mask budget check.

`ctx` fails the test when the GL error flag is set before or after it (as moderngl's own
conftest does), so a test cannot leave an error behind for the next one to trip over.  A missing
EGL driver fails loudly: it never skips.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from scipy.ndimage import maximum_filter, minimum_filter

ROOT = Path(__file__).resolve().parent.parent
TEST_OUTPUT = ROOT / "test-output"

# The budget of CONVENTIONS-style mask comparisons (issue 3): zero mismatches farther than one
# pixel from a mask edge, and fewer than this fraction of all pixels mismatched.
MAX_MISMATCH_FRACTION = 0.001


@pytest.fixture(scope="session")
def gl_session():
    from shadowvol.context import create_context

    ctx = create_context()  # raises ContextError (the test errors) when EGL/GL 4.5 is missing
    yield ctx
    ctx.release()


@pytest.fixture
def ctx(gl_session):
    from shadowvol.context import make_current

    make_current(gl_session)  # a test that made its own context may have left that one current
    before = gl_session.error
    if before != "GL_NO_ERROR":
        pytest.fail(f"GL error flag set before the test: {before}")
    yield gl_session
    after = gl_session.error
    if after != "GL_NO_ERROR":
        pytest.fail(f"GL error flag set by the test: {after}")


def edge_pixels(mask: np.ndarray) -> np.ndarray:
    """(H, W) bool: pixels whose 3x3 neighbourhood in `mask` is not uniform."""
    m = mask.astype(np.uint8)
    return maximum_filter(m, 3, mode="nearest") != minimum_filter(m, 3, mode="nearest")


def mask_report(got_lit, got_cov, ref_lit, ref_cov) -> list[dict]:
    """Per light (and one entry for coverage): mismatched pixels in total and in the interior
    (farther than one pixel from an edge of the lit or coverage mask in either image)."""
    near_cov = edge_pixels(ref_cov) | edge_pixels(got_cov)
    rows = [{"what": "coverage", "total": int((got_cov != ref_cov).sum()),
             "interior": int(((got_cov != ref_cov) & ~near_cov).sum())}]
    for i in range(len(ref_lit)):
        near = near_cov | edge_pixels(ref_lit[i]) | edge_pixels(got_lit[i])
        bad = got_lit[i] != ref_lit[i]
        rows.append({"what": f"light {i}", "total": int(bad.sum()),
                     "interior": int((bad & ~near).sum())})
    return rows


def diff_image(got_lit, got_cov, ref_lit, ref_cov) -> np.ndarray:
    """(H, L*W, 3) uint8: white both lit, grey both shadowed, black both uncovered, red shadowed
    only in the raster, blue shadowed only in the reference, yellow coverage differs."""
    panels = []
    for g, r in zip(got_lit, ref_lit):
        p = np.zeros(g.shape + (3,), np.uint8)
        p[ref_cov & got_cov] = 96
        p[g & r] = 255
        p[~g & r] = (230, 30, 30)
        p[g & ~r] = (40, 80, 255)
        p[got_cov != ref_cov] = (255, 220, 0)
        panels.append(p)
    return np.concatenate(panels, axis=1) if panels else np.zeros((1, 1, 3), np.uint8)


@pytest.fixture
def assert_masks_match(request):
    """assert_masks_match(result, ref_lit, ref_cov, label="") checks the budget; on failure
    writes render.png, masks.png, reference.png and diff.png under test-output/<test>/."""

    def check(result, ref_lit, ref_cov, label: str = "") -> list[dict]:
        rows = mask_report(result.lit, result.coverage, ref_lit, ref_cov)
        pixels = ref_cov.size
        interior = sum(r["interior"] for r in rows)
        worst = max(r["total"] for r in rows)
        if interior == 0 and worst < MAX_MISMATCH_FRACTION * pixels:
            return rows
        from shadowvol.files import masks_image, save_png

        name = re.sub(r"[^A-Za-z0-9_.-]+", "_", request.node.name + (f"-{label}" if label else ""))
        out = TEST_OUTPUT / name
        save_png(out / "render.png", result.image)
        save_png(out / "masks.png", masks_image(result.lit, result.coverage))
        save_png(out / "reference.png", masks_image(ref_lit, ref_cov))
        save_png(out / "diff.png", diff_image(result.lit, result.coverage, ref_lit, ref_cov))
        pytest.fail(f"masks differ beyond the budget ({label}): {rows}; budget: 0 interior, "
                    f"< {MAX_MISMATCH_FRACTION * pixels:.1f} in total per mask; "
                    f"images written to {out}")

    return check
