"""--format webdataset: tar shards of a fixed number of samples that the `webdataset` package
reads back to the very arrays of the per-frame files; shards of a job file make the same tars."""

from __future__ import annotations

import io

import numpy as np
import pytest
from builders import job_lines, output_files, write_jobs
from PIL import Image

from shadowvol import batch

pytestmark = pytest.mark.gl


def test_webdataset_round_trip_and_shards(tmp_path, compare_outputs):
    webdataset = pytest.importorskip("webdataset", reason="the webdataset package is not "
                                     "installed (pip install 'shadowvol[test]')")
    jobs = write_jobs(tmp_path / "jobs.jsonl", job_lines(frames=5, size=(32, 24)))
    files, tars = tmp_path / "files", tmp_path / "tars"
    assert batch.run(jobs, files, progress=False).status == 0
    summary = batch.run(jobs, tars, format="webdataset", samples_per_tar=3, progress=False)
    assert summary.status == 0 and summary.rendered == 7
    assert sorted(output_files(tars)) == ["shard-000000.tar", "shard-000001.tar",
                                          "shard-000002.tar"]

    urls = [str(tars / f"shard-{i:06d}.tar") for i in range(3)]
    samples = list(webdataset.WebDataset(urls, shardshuffle=False))
    per_frame = output_files(files)
    keys = [f"cage-turntable/{i:06d}" for i in range(5)] + [f"cage-traced/{i:06d}" for i in (0, 1)]
    assert [s["__key__"] for s in samples] == keys  # every frame once, in job-file order
    for sample in samples:
        key = sample["__key__"]
        assert sample["png"] == per_frame[f"{key}.png"]  # the same bytes as the file
        assert sample["masks.npz"] == per_frame[f"{key}.masks.npz"]

    decoded = list(webdataset.WebDataset(urls, shardshuffle=False).decode("rgb8"))
    for sample in decoded:
        key = sample["__key__"]
        want = np.asarray(Image.open(io.BytesIO(per_frame[f"{key}.png"])).convert("RGB"))
        assert np.array_equal(sample["png"], want)
        with np.load(io.BytesIO(per_frame[f"{key}.masks.npz"])) as masks:
            assert np.array_equal(sample["masks.npz"]["lit"], masks["lit"])
            assert sample["masks.npz"]["coverage"].dtype == bool

    # two shards of the job file make the same three tars (a shard is whole tars)
    sharded = tmp_path / "sharded"
    for i in (0, 1):
        assert batch.run(jobs, sharded, format="webdataset", samples_per_tar=3, shard=(i, 2),
                         progress=False).status == 0
    assert output_files(sharded) == output_files(tars)
    rerun = batch.run(jobs, sharded, format="webdataset", samples_per_tar=3, progress=False)
    assert (rerun.rendered, rerun.skipped) == (0, 7)
    compare_outputs(sharded, tars)
