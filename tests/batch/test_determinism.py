"""The same job file makes byte-identical files and manifest hashes with 1 worker, 2 worker
processes, shards 0/2 + 1/2, and 2 Ray actors (a local Ray, ray.init(num_cpus=2))."""

from __future__ import annotations

import pytest
from builders import job_lines, manifest_hashes, output_files, write_jobs

from shadowvol import batch

pytestmark = pytest.mark.gl


@pytest.fixture(scope="module")
def reference(tmp_path_factory, request):
    folder = tmp_path_factory.mktemp("reference")
    jobs = write_jobs(folder / "jobs.jsonl", job_lines())
    summary = batch.run(jobs, folder / "out", progress=False)
    assert summary.status == 0 and summary.rendered == 6, summary.errors
    return jobs, folder / "out"


def test_one_run_makes_every_file_the_manifest_lists(reference):
    _, out = reference
    files = output_files(out)
    assert len(files) == 12  # 6 frames x (png + npz)
    assert {k.split("/")[0] for k in files} == {"cage-turntable", "cage-traced"}
    assert [row[0] for row in manifest_hashes(out)][::2] == \
        [f"cage-turntable/{i:06d}" for i in range(4)] + [f"cage-traced/{i:06d}" for i in range(2)]


@pytest.mark.parametrize("start_method", ["spawn", "forkserver"])
def test_two_worker_processes(reference, tmp_path, compare_outputs, start_method):
    jobs, ref = reference
    summary = batch.run(jobs, tmp_path / "out", workers=2, start_method=start_method,
                        progress=False)
    assert summary.status == 0 and summary.rendered == 6
    compare_outputs(tmp_path / "out", ref)


def test_shards_together_are_one_run(reference, tmp_path, compare_outputs):
    jobs, ref = reference
    out = tmp_path / "out"
    made = [batch.run(jobs, out, shard=(i, 2), progress=False) for i in (0, 1)]
    assert [s.rendered for s in made] == [3, 3] and all(s.status == 0 for s in made)
    assert sorted(p.name for p in out.glob("manifest*")) == \
        ["manifest.shard-0-of-2.jsonl", "manifest.shard-1-of-2.jsonl"]
    merged = batch.run(jobs, out, progress=False)  # checks the shards' files, makes nothing
    assert (merged.rendered, merged.skipped, merged.status) == (0, 6, 0)
    compare_outputs(out, ref)


def test_ray_actors(reference, tmp_path, compare_outputs, ray_session):
    jobs, ref = reference
    summary = batch.run(jobs, tmp_path / "out", workers=2, ray=True, progress=False)
    assert summary.status == 0 and summary.rendered == 6, summary.errors
    compare_outputs(tmp_path / "out", ref)
