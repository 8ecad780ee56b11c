"""A job of renderer "auto": the masks alone, each frame by the renderer the cost model of
`shadowvol.compare.fastest` takes on the worker, said in the frame's manifest line
(`versions.masks_by`), and byte for byte what a job naming that renderer makes; "auto" with
any other output is a bad job (status 2); without a GL the ray tracer makes the masks."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from builders import ROOT, SCENES, write_jobs

from shadowvol import batch
from shadowvol.cli import status
from shadowvol.compare import fastest
from shadowvol.scenefile import load_scene

NO_EGL = {"__EGL_VENDOR_LIBRARY_FILENAMES": "/nonexistent.json"}


def masks_job(renderer: str, size=(64, 48), name: str = "masks") -> dict:
    return {"name": name, "scene": str(SCENES / "cage.toml"), "size": list(size),
            "cameras": {"orbit": {"center": [-0.6, 1.0, -0.8], "radius": 7.0,
                                  "elevation": 30.0, "frames": 2}},
            "outputs": ["masks"], "renderer": renderer}


def records(out) -> dict:
    return {r["id"]: r for r in map(json.loads, (out / "manifest.jsonl").read_text()
                                    .splitlines())}


@pytest.mark.gl
@pytest.mark.parametrize("size", [(64, 48), (1280, 720)])
def test_auto_makes_what_the_renderer_it_names_makes(tmp_path, size):
    scene = load_scene(SCENES / "cage.toml").replace(width=size[0], height=size[1])
    from shadowvol.raster.platform.context import create_context

    ctx = create_context()
    try:
        expected = fastest.choose_for(scene, "auto", ctx.info["GL_RENDERER"],
                                      first=False).renderer
    finally:
        ctx.release()
    assert batch.run([masks_job("auto", size)], tmp_path / "auto", progress=False).status == 0
    assert batch.run([masks_job(expected, size)], tmp_path / "named",
                     progress=False).status == 0
    auto, named = records(tmp_path / "auto"), records(tmp_path / "named")
    assert len(auto) == 2
    for key, record in auto.items():
        assert record["renderer"] == "auto" and record["versions"]["masks_by"] == expected
        path = record["files"]["masks"]["path"]
        assert path == named[key]["files"]["masks"]["path"]
        assert (tmp_path / "auto" / path).read_bytes() == (tmp_path / "named" / path).read_bytes()


@pytest.mark.gl
def test_the_model_s_choice_depends_on_the_frame(tmp_path):
    """A small frame and a large one of the cage: the ray tracer's setup is cheaper, the
    rasterizer's pixels are (the model, warm, on llvmpipe): two renderers in one run."""
    small, large = (fastest.choose("auto", 990, w * h, 1, "llvmpipe (LLVM)", "packets",
                                   first=False).renderer for w, h in ((64, 48), (1280, 720)))
    assert (small, large) == ("raytrace", "shadowvol")


def test_auto_with_another_output_is_a_bad_job(tmp_path):
    job = dict(masks_job("auto"), outputs=["image", "masks"])
    summary = batch.run([job], tmp_path / "out", progress=False)
    assert summary.status == status.BAD_INPUT
    error = records(tmp_path / "out")["job/masks"]["error"]
    assert error.startswith("renderer: auto chooses the renderer of the masks alone")
    assert "['image', 'masks']" in error


def test_auto_without_a_gl_traces_the_masks(tmp_path):
    jobs = write_jobs(tmp_path / "jobs.jsonl", [masks_job("auto")])
    done = subprocess.run([sys.executable, "-m", "shadowvol", "batch", str(jobs), "-o",
                           str(tmp_path / "out")], cwd=tmp_path, capture_output=True, text=True,
                          timeout=300, env={**os.environ, "PYTHONPATH": str(ROOT), **NO_EGL})
    assert done.returncode == 0, done.stderr[-3000:]
    found = records(tmp_path / "out")
    assert [r["versions"]["masks_by"] for r in found.values()] == ["raytrace", "raytrace"]
