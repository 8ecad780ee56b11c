"""The outputs are a table: an output added there (as the ground-truth outputs will be) flows
through jobs, files, the manifest, resume and the webdataset tars with no other change; the
progress bar shows only on a terminal."""

from __future__ import annotations

import io
import json
import sys

import numpy as np
import pytest
from builders import SCENES, job_lines
from PIL import Image

import shadowvol.batch as batch
from shadowvol.batch import outputs, runner
from shadowvol.batch.outputs import Output
from shadowvol.io import png_bytes


@pytest.mark.gl
def test_a_new_output_flows_through(tmp_path, monkeypatch):
    extra = Output("coverage", "coverage.png", ("coverage",),
                   lambda f: png_bytes(f["coverage"]), "coverage as a black/white PNG")
    monkeypatch.setitem(outputs.OUTPUTS, "coverage", extra)
    job = dict(job_lines(frames=2, size=(32, 24), raytrace=False)[0],
               outputs=["image", "coverage", "masks"])
    out = tmp_path / "out"
    assert batch.run([job], out, progress=False).status == 0  # in this process: the table
    record = json.loads((out / "manifest.jsonl").read_text().splitlines()[0])
    assert set(record["files"]) == {"image", "coverage", "masks"}
    picture = np.asarray(Image.open(out / record["files"]["coverage"]["path"]))
    with np.load(out / record["files"]["masks"]["path"]) as masks:
        assert np.array_equal(picture, masks["coverage"].astype(np.uint8) * 255)
    assert batch.run([job], out, progress=False).skipped == 2
    tars = batch.run([job], tmp_path / "tars", format="webdataset", progress=False)
    assert tars.status == 0
    import tarfile

    with tarfile.open(tmp_path / "tars" / "shard-000000.tar") as archive:
        names = archive.getnames()
        data = archive.extractfile("cage-turntable/000000.coverage.png").read()
    assert "cage-turntable/000001.coverage.png" in names
    assert np.array_equal(np.asarray(Image.open(io.BytesIO(data))), picture)


def test_the_progress_bar_only_on_a_terminal(monkeypatch):
    pytest.importorskip("tqdm", reason="tqdm is not installed (pip install 'shadowvol[tqdm]')")
    monkeypatch.setattr(sys.stderr, "isatty", lambda: False, raising=False)
    assert runner._bar(10, None) is None and runner._bar(10, False) is None
    bar = runner._bar(10, True)
    assert bar is not None and bar.total == 10
    bar.close()


def test_the_benchmark_says_when_the_models_are_missing(tmp_path):
    from benchmarks import bench_batch

    assert "the shared models are missing" in bench_batch.measure(models=tmp_path)["skipped"]


@pytest.mark.gl
def test_the_ground_truth_flows_through_from_both_renderers(tmp_path, ctx):
    """Every ground-truth output is a file of the frame, equal to what the renderer gives for
    the same frame; the mask file holds the camera, as every mask file does."""
    import raytrace
    from shadowvol.frame import GROUND_TRUTH
    from shadowvol.io import load_mask_arrays
    from shadowvol.raster.renderer import Renderer
    from shadowvol.scene import Camera
    from shadowvol.scenefile import load_scene

    view = {"eye": [4.0, 3.0, 5.0], "target": [0.0, 1.0, 0.0]}
    jobs = [{"name": name, "scene": str(SCENES / "stack.toml"), "size": [40, 30],
             "renderer": name, "cameras": [view], "outputs": ["masks", *GROUND_TRUTH]}
            for name in ("shadowvol", "raytrace")]
    batch.run(jobs, tmp_path / "out")
    base = load_scene(SCENES / "stack.toml").replace(width=40, height=30)
    scene = base.replace(camera=Camera(**{"up": base.camera.up, "fov_y": base.camera.fov_y,
                                          "near": base.camera.near, **view}))
    with Renderer(scene, ctx) as r:
        raster = r.render(outputs=("lit", "coverage", *GROUND_TRUTH))
    traced = raytrace.ground_truth(scene, outputs=GROUND_TRUTH)
    for job, want in (("shadowvol", raster), ("raytrace", traced)):
        folder = tmp_path / "out" / job
        for name in GROUND_TRUTH:
            np.testing.assert_array_equal(np.load(folder / f"000000.{name}.npy"),
                                          getattr(want, name), err_msg=f"{job} {name}")
        masks = load_mask_arrays(folder / "000000.masks.npz")
        np.testing.assert_array_equal(masks["lit"], want.lit)
        np.testing.assert_allclose(masks["K"], traced.calibration.K)
