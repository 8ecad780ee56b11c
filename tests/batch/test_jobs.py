"""Jobs without GL: camera generators, stable ids, specs and their hashes, shards, the seeded
per-frame generator, EGL device choice, and the deterministic encoders."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest
from builders import SCENES, job_lines

from shadowvol.batch import egl, job_frames
from shadowvol.batch.jobs import Job, JobError, check_jobs, read_jobs
from shadowvol.batch.runner import parse_shard, share
from shadowvol.errors import InputError
from shadowvol.io import npz_bytes, tar_bytes
from shadowvol.raster.platform.egl import Device, devices
from shadowvol.scene import Camera, PointLight, SceneError


def test_orbit_is_a_turntable():
    cams = job_frames.orbit({"center": [1, 2, 3], "radius": 4, "elevation": 30, "frames": 8})
    assert len(cams) == 8
    for i, cam in enumerate(cams):
        offset = np.subtract(cam["eye"], [1, 2, 3])
        assert np.isclose(np.linalg.norm(offset), 4)
        assert np.isclose(math.degrees(math.asin(offset[1] / 4)), 30)
        assert np.isclose(math.degrees(math.atan2(offset[0], offset[2])) % 360, 45 * i)
        assert cam["target"] == [1.0, 2.0, 3.0]


def test_path_goes_through_its_keys():
    keys = [{"eye": [0, 1, 5], "target": [0, 0, 0], "fov_y": 40},
            {"eye": [5, 1, 0], "target": [0, 0, 0], "fov_y": 60},
            {"eye": [0, 1, -5], "target": [0, 1, 0], "fov_y": 50}]
    cams = job_frames.path({"keys": keys, "frames": 5})
    assert cams[0]["eye"] == [0, 1, 5] and cams[2]["eye"] == [5, 1, 0]
    assert cams[4]["eye"] == [0, 1, -5] and cams[4]["fov_y"] == 50
    assert cams[1]["eye"] == [2.5, 1, 2.5] and cams[1]["fov_y"] == 50


def test_jobs_are_checked_with_messages_that_name_the_key(tmp_path):
    good = job_lines(frames=3, raytrace=False)[0]
    entries = check_jobs([good, dict(good), dict(good, name="x", outputs=["depthh"]),
                          dict(good, name="y", size=[0, 4]),
                          dict(good, name="z", lights=[{"type": "point"}]),
                          dict(good, name="w", cameras=[{"eye": [0, 0, 1], "target": [0, 0, 1]}]),
                          dict(good, name="bad name")])
    assert isinstance(entries[0], Job) and len(entries[0].cameras) == 3
    errors = [e.error for e in entries[1:]]
    assert all(isinstance(e, JobError) for e in entries[1:])
    assert "also the name of the job" in errors[0]
    assert "unknown output 'depthh'" in errors[1]
    assert errors[2].startswith("size[0]") and "position" in errors[3]
    assert "eye and target are the same point" in errors[4]
    assert errors[5].startswith("name")
    path = tmp_path / "jobs.jsonl"
    path.write_text('# a comment\n\n{"scene": "cage.toml", "cameras": []}\n[1]\n')
    read = read_jobs(path)
    assert [e.source for e in read] == [f"{path}:3", f"{path}:4"]
    with pytest.raises(SceneError, match="cannot read the job file"):
        read_jobs(tmp_path / "absent.jsonl")


def test_ids_and_spec_hashes_are_stable():
    job = check_jobs([job_lines(frames=3, raytrace=False)[0]])[0]
    specs = job_frames.specs(job, "key")
    assert [s.id for s in specs] == [f"cage-turntable/{i:06d}" for i in range(3)]
    again = job_frames.specs(check_jobs([job_lines(frames=3, raytrace=False)[0]])[0], "other key")
    assert [job_frames.spec_hash(s, "d") for s in specs] == [job_frames.spec_hash(s, "d") for s in again]
    assert job_frames.spec_hash(specs[0], "d") != job_frames.spec_hash(specs[0], "e")
    assert len({job_frames.spec_hash(s, "d") for s in specs}) == 3
    assert job.scene == str((SCENES / "cage.toml").resolve())


@pytest.mark.parametrize("units", [0, 1, 5, 36, 101])
@pytest.mark.parametrize("count", [1, 2, 3, 7])
def test_shards_cover_every_unit_once(units, count):
    covered = [u for i in range(count) for u in share(units, (i, count))]
    assert covered == list(range(units))
    assert parse_shard(f"{count - 1}/{count}") == (count - 1, count)
    with pytest.raises(InputError):
        parse_shard(f"{count}/{count}")


def test_jitter_depends_only_on_seed_and_index():
    camera = Camera(eye=[0, 1, 5], target=[0, 0, 0])
    lights = (PointLight([0, 3, 0]),)
    a = job_frames.jittered(camera, lights, {"eye": 0.5, "lights": 0.2}, 3, 10)
    job_frames.jittered(camera, lights, {"eye": 0.5, "lights": 0.2}, 3, 11)  # another frame first
    b = job_frames.jittered(camera, lights, {"eye": 0.5, "lights": 0.2}, 3, 10)
    assert np.array_equal(a[0].eye, b[0].eye) and np.array_equal(a[1][0].position,
                                                                 b[1][0].position)
    assert 0 < np.linalg.norm(a[0].eye - camera.eye) <= 0.5
    assert 0 < np.linalg.norm(a[1][0].position - lights[0].position) <= 0.2


def test_egl_device_choice():
    mesa = Device(2, ("EGL_MESA_device_software",), None, None, None)
    gpus = [Device(0, ("EGL_NV_device_cuda",), "/dev/dri/card1", "H200", 1),
            Device(1, ("EGL_NV_device_cuda",), "/dev/dri/card0", "H200", 0), mesa]
    assert egl.choose("auto", gpus)[0] == 1  # CUDA device 0, wherever EGL lists it
    assert egl.choose("auto", [mesa])[0] == 0
    assert egl.choose("2", gpus)[0] == 2
    with pytest.raises(InputError, match=r"no EGL device 3; this machine has 3: 0 \(H200, CUDA "
                                         r"device 1\), 1 \(H200, CUDA device 0\), 2 \(Mesa"):
        egl.choose(3, gpus)
    for bad in ("-1", "gpu0", True, 1.5):
        with pytest.raises(InputError, match="--egl-device"):
            egl.choose(bad, gpus)
    found = devices()  # this machine's, by the real queries
    assert all(d.index == i for i, d in enumerate(found))


def test_encoders_are_deterministic_and_readable():
    arrays = {"lit": np.eye(3, dtype=bool)[None], "depth": np.linspace(0, 1, 6).reshape(2, 3)}
    data = npz_bytes(**arrays)
    assert data == npz_bytes(**arrays)
    with np.load(io.BytesIO(data), allow_pickle=False) as back:
        assert all(np.array_equal(back[k], v) for k, v in arrays.items())
    assert tar_bytes([("a/1.png", b"x")]) == tar_bytes([("a/1.png", b"x")])


def test_the_example_job_file_is_a_turntable_of_an_example_scene():
    (job,) = read_jobs(SCENES / "turntable.jsonl")
    assert isinstance(job, Job), job
    assert job.outputs == ("image", "masks") and 2 <= len(job.cameras) <= 12
    assert job.scene == str((SCENES / "cage.toml").resolve())
