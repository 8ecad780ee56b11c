"""Shared fixtures: the one GL context of the session, and the mask budget check.

`ctx` fails the test when the GL error flag is set before or after it (as moderngl's own
conftest does), so a test cannot leave an error behind for the next one to trip over.  A missing
EGL driver fails loudly: it never skips.

The `gl` marker: every test under raster/ and compare/, every test that uses `ctx`, and every
module that says `pytestmark = pytest.mark.gl` needs a GL context; `pytest -m "not gl"` runs
the rest, and for those the context factory is blocked, so a test that needs GL but is not
marked fails instead of passing by luck.  A module of raster/ or compare/ that says
`FOLDER_GL = False` renders only through `ctx`: its other tests run unmarked, with GL blocked.  Child processes are not covered by that block: run
`__EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent.json pytest -m "not gl"` (EGL then finds no
driver anywhere) to check that no unmarked test starts a process that renders.

The `alone` marker (tests/alone.py): under pytest-xdist a test so marked runs with no test of
another worker beside it.  Before the workers start, numba's disk cache is made once where
the checkout has none (tests/warmup.py).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import warmup
from alone import pytest_configure, pytest_runtest_protocol  # noqa: F401 (the hooks)
from builders import TEST_OUTPUT

# the one definition of a mask edge and of the mismatch report (shared with `compare`)
from shadowvol.compare.maskdiff import diff_image, edge_pixels, mask_report  # noqa: F401
from shadowvol.io import save_png
from shadowvol.pictures import masks_image

GL_FOLDERS = ("raster", "compare")

# The budget of CONVENTIONS-style mask comparisons (issue 3): zero mismatches farther than one
# pixel from a mask edge, and fewer than this fraction of all pixels mismatched.
MAX_MISMATCH_FRACTION = 0.001


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_setupnodes(config, specs):
    """Before pytest-xdist starts its workers (in the session's time, which it reports):
    numba's disk cache made once where the checkout has none (tests/warmup.py)."""
    if warmup.cold():
        report = config.pluginmanager.get_plugin("terminalreporter")
        if report is not None:
            report.write_line("compiling numba's kernels once, before the workers start "
                              "(tests/warmup.py; about a minute on a fresh checkout)")
        warmup.warm()


def pytest_collection_modifyitems(config, items):
    for item in items:
        folder = Path(str(item.fspath)).parent.name
        by_folder = folder in GL_FOLDERS and getattr(item.module, "FOLDER_GL", True)
        if by_folder or {"ctx", "gl_session"} & set(item.fixturenames):
            item.add_marker(pytest.mark.gl)


@pytest.fixture(autouse=True)
def _no_gl_unless_marked(request, monkeypatch):
    if request.node.get_closest_marker("gl") is None:
        import moderngl

        def refuse(*args, **kwargs):
            raise AssertionError("this test makes a GL context but is not marked `gl`")
        monkeypatch.setattr(moderngl, "create_context", refuse)
    yield


@pytest.fixture(params=["numpy", "numba"])
def path_shading(request, monkeypatch):
    """The path tracer's per-bounce shading (`raytrace.outlook.path.pathtrace.shading`), set for the
    test through $SHADOWVOL_PATHTRACE: a test that takes this runs on both; the numba one skips,
    saying why, where numba is not installed (the `fast` extra; the `test` extra has it)."""
    if request.param == "numba":
        pytest.importorskip("numba", reason="the numba shading needs numba: "
                            "pip install 'shadowvol[fast]'")
    monkeypatch.setenv("SHADOWVOL_PATHTRACE", request.param)
    return request.param


@pytest.fixture(scope="session")
def gl_session():
    from shadowvol.raster.platform.context import create_context

    ctx = create_context()  # raises ContextError (the test errors) when EGL/GL 4.5 is missing
    yield ctx
    ctx.release()


@pytest.fixture
def ctx(gl_session):
    from shadowvol.raster.platform.context import make_current

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
