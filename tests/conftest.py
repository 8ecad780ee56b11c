"""Shared fixtures: the one GL context of the session, and the mask budget check.

`ctx` fails the test when the GL error flag is set before or after it (as moderngl's own
conftest does), so a test cannot leave an error behind for the next one to trip over.  A missing
EGL driver fails loudly: it never skips.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

# the one definition of a mask edge and of the mismatch report (shared with `compare`)
from shadowvol.maskdiff import diff_image, edge_pixels, mask_report  # noqa: F401

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
