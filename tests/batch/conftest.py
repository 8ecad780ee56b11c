"""Fixtures of the batch tests: a small job file, and a check that two output folders hold the
same files and manifest hashes."""

from __future__ import annotations

from pathlib import Path

import pytest
from builders import job_lines, manifest_hashes, output_files, write_jobs


@pytest.fixture(scope="session")
def ray_session():
    """One local Ray (2 CPUs) for the batch tests that use it, shut down after them."""
    ray = pytest.importorskip("ray", reason="ray is not installed here (pip install "
                                            "'shadowvol[ray]'): only the Ray runs are skipped")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield ray
    ray.shutdown()


@pytest.fixture
def jobs_file(tmp_path) -> Path:
    return write_jobs(tmp_path / "jobs.jsonl", job_lines())


@pytest.fixture
def compare_outputs():
    def check(out: Path, reference: Path, name: str = "manifest.jsonl") -> None:
        got, want = output_files(out), output_files(reference)
        assert sorted(got) == sorted(want), "different files"
        differ = [k for k in want if got[k] != want[k]]
        assert not differ, f"files whose bytes differ: {differ}"
        assert manifest_hashes(out, name) == manifest_hashes(reference)
    return check
