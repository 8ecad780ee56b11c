"""The trap of the issue: a pool forked after the parent made a GL context hangs.  The batch
workers are spawned, so they work after the parent rendered; forked ones fail at once, with the
error that says why and what to do, instead of hanging."""

from __future__ import annotations

import json

import pytest
from builders import job_lines, tiny_scene

from shadowvol import batch
from shadowvol.cli import status
from shadowvol.raster.renderer import Renderer

pytestmark = pytest.mark.gl


def test_workers_after_the_parent_made_a_context(tmp_path):
    jobs = job_lines(frames=2, size=(32, 24), raytrace=False)
    with Renderer(tiny_scene()) as renderer:  # this process now holds an EGL context
        renderer.render()
        spawned = batch.run(jobs, tmp_path / "spawned", workers=2, progress=False)
        assert spawned.status == status.OK and spawned.rendered == 2

        forked = batch.run(jobs, tmp_path / "forked", workers=1, start_method="fork",
                           progress=False)
    assert forked.status == status.RENDER_FAILED and forked.failed == 2
    record = json.loads((tmp_path / "forked" / "manifest.jsonl").read_text().splitlines()[0])
    assert "forked after its parent made an OpenGL context" in record["error"]
    assert "spawn" in record["error"]
