"""Job lines built to break the reader (issue 36, step 6): each is one bad job, recorded with a
one-line error naming the job file's line, and the other jobs are made.  No GL: the frames
are ray traced."""

from __future__ import annotations

import json

from builders import SCENES

from shadowvol.batch.jobs import Job, JobError, read_jobs
from shadowvol.cli import status
from shadowvol.cli.main import main

GOOD = {"name": "good", "scene": str(SCENES / "cage.toml"),
        "cameras": {"orbit": {"center": [0, 1, 0], "radius": 6, "frames": 1}},
        "size": [8, 6], "outputs": ["masks"], "renderer": "raytrace", "max_depth": 0}


def deep_jobs(tmp_path):
    """Line 1 nested 100,000 deep (past json's recursion), line 2 500 deep (parsed, past the
    scene files' limit of 16), line 3 a good job."""
    deep = '{"name": "deep", "lights": ' + "[" * 100_000 + "]" * 100_000 + "}"
    mid = json.dumps(dict(GOOD, name="mid", lights=json.loads("[" * 500 + "]" * 500)))
    path = tmp_path / "jobs.jsonl"
    path.write_text(f"{deep}\n{mid}\n{json.dumps(GOOD)}\n")
    return path


def test_a_job_nested_100000_deep_is_one_bad_job(tmp_path):
    path = deep_jobs(tmp_path)
    deep, mid, good = read_jobs(path)
    assert isinstance(deep, JobError) and deep.source == f"{path}:1"
    assert deep.error == "nested more than 16 levels deep"
    assert isinstance(mid, JobError) and mid.name == "mid"
    assert mid.error.endswith("]: nested more than 16 levels deep") and \
        mid.error.startswith("lights[0][0]"), mid.error
    assert isinstance(good, Job)


def test_the_batch_records_it_and_makes_the_others(tmp_path, capsys):
    path = deep_jobs(tmp_path)
    out = tmp_path / "out"
    assert main(["batch", str(path), "-o", str(out), "--no-progress"]) == status.BAD_INPUT
    err = capsys.readouterr().err
    assert f"error: {path}:1: nested more than 16 levels deep\n" in err
    assert "Traceback" not in err and "RecursionError" not in err
    records = [json.loads(line) for line in (out / "manifest.jsonl").open()]
    assert [r["id"] for r in records] == ["job/line-1", "job/mid", "good/000000"]
    assert "error" not in records[2] and (out / records[2]["files"]["masks"]["path"]).is_file()


def test_jitter_past_float32_names_jitter(tmp_path):
    """A radius past the renderers' float32 range is a bad job (`jitter.eye`); one within it
    that moves an eye near the range's edge out of it fails that frame naming `jitter.eye`
    and the eye as a list (was: `eye: array([...]) is beyond ...`, no word of jitter)."""
    far = dict(GOOD, name="far", cameras=[{"eye": [9.9e17, 0, 0], "target": [0, 0, 0]}] * 4,
               jitter={"eye": 5e17})
    huge = dict(GOOD, name="huge", jitter={"lights": 1e300})
    path = tmp_path / "jobs.jsonl"
    path.write_text(f"{json.dumps(far)}\n{json.dumps(huge)}\n")
    far_job, huge_job = read_jobs(path)
    assert isinstance(far_job, Job)
    assert isinstance(huge_job, JobError) and huge_job.error == (
        "jitter.lights: a radius of 1e+300 would move the lights beyond the float32 range the "
        "renderers use (|x| <= 1e+18)")
    out = tmp_path / "out"
    assert main(["batch", str(path), "-o", str(out), "--no-progress"]) == status.BAD_INPUT
    records = [json.loads(line) for line in (out / "manifest.jsonl").open()]
    failed = [r["error"] for r in records if r["id"].startswith("far/") and "error" in r]
    assert failed, "no frame's eye left the float32 range: the test needs another seed"
    for error in failed:
        assert error.startswith("jitter.eye: a radius of 5e+17 moved the eye out of range: "
                                "eye: [") and "array(" not in error, error


def test_object_jitter_past_float32_names_jitter(tmp_path):
    """The objects' translation radius past the renderers' float32 range is a bad job naming
    `jitter.objects.translation` (was: each frame failing on `pose: [[...]]`, no word of
    jitter)."""
    huge = dict(GOOD, name="huge", jitter={"objects": {"translation": 1e39}})
    path = tmp_path / "jobs.jsonl"
    path.write_text(f"{json.dumps(huge)}\n")
    (job,) = read_jobs(path)
    assert isinstance(job, JobError) and job.error == (
        "jitter.objects.translation: a radius of 1e+39 would move the objects beyond the "
        "float32 range the renderers use (|x| <= 1e+18)")
