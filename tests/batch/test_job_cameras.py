"""A job's cameras are look-at cameras or, as a scene file's, intrinsics fx, fy, cx, cy and a
pose camera_to_world (docs/datasets.md): the K and camera_to_world a job frame writes, given
back as a job's camera, make the same masks bit for bit (with the principal point off the
centre and non-square pixels too); eye jitter moves a matrix camera's whole pose and keeps its
axes; a camera that mixes the forms, misses a key or is not rigid is refused naming the key."""

from __future__ import annotations

import json

import numpy as np
import pytest
from builders import SCENES

from shadowvol import batch
from shadowvol.batch.jobs import JobError, check_jobs

pytestmark = pytest.mark.gl

LOOK_AT = {"eye": [4.2, 3.4, 5.2], "target": [-0.6, 1.0, -0.8]}


def _matrix_camera(npz) -> dict:
    K, c2w = npz["K"], npz["camera_to_world"]
    return {"fx": float(K[0, 0]), "fy": float(K[1, 1]), "cx": float(K[0, 2]),
            "cy": float(K[1, 2]), "camera_to_world": c2w.tolist()}


def _records(out) -> dict:
    return {r["id"]: r for r in map(json.loads, (out / "manifest.jsonl").read_text()
                                    .splitlines())}


@pytest.mark.parametrize("renderer", ["shadowvol", "raytrace"])
def test_written_matrices_given_back_as_a_job_camera_make_the_same_masks(tmp_path, renderer):
    base = {"scene": str(SCENES / "calibrated.toml"), "size": [40, 30], "renderer": renderer,
            "max_depth": 0, "outputs": ["masks"]}
    assert batch.run([dict(base, name="look-at", cameras=[LOOK_AT])], tmp_path / "a",
                     progress=False).status == 0
    # a job camera off-centre, non-square (the scene's): what it writes, given back
    scene_job = dict(base, name="scene-camera", cameras=[_scene_camera()])
    assert batch.run([scene_job], tmp_path / "s", progress=False).status == 0
    for out, job in ((tmp_path / "a", "look-at"), (tmp_path / "s", "scene-camera")):
        made = np.load(out / job / "000000.masks.npz")
        again = dict(base, name="again", cameras=[_matrix_camera(made)])
        summary = batch.run([again], tmp_path / f"b-{job}", progress=False)
        assert summary.status == 0, summary.errors
        back = np.load(tmp_path / f"b-{job}" / "again" / "000000.masks.npz")
        assert made["coverage"].any()
        assert np.array_equal(back["coverage"], made["coverage"])
        assert np.array_equal(back["lit"], made["lit"])
        assert np.array_equal(back["K"], made["K"])
        assert np.array_equal(back["camera_to_world"], made["camera_to_world"])
        camera = _records(tmp_path / f"b-{job}")["again/000000"]["camera"]
        assert camera["fx"] == again["cameras"][0]["fx"] and camera["fov_y"] is None


def _scene_camera() -> dict:
    """calibrated.toml's camera, its intrinsics scaled from 640 x 480 to 40 x 30."""
    import tomllib

    camera = tomllib.loads((SCENES / "calibrated.toml").read_text())["camera"]
    s = 40 / 640
    return {"fx": camera["fx"] * s, "fy": camera["fy"] * s, "cx": camera["cx"] * s,
            "cy": camera["cy"] * s, "camera_to_world": camera["camera_to_world"]}


def test_eye_jitter_moves_a_matrix_cameras_pose_and_keeps_its_axes(tmp_path):
    camera = _scene_camera()
    job = {"name": "shaky", "scene": str(SCENES / "calibrated.toml"), "size": [40, 30],
           "outputs": ["masks"], "seed": 4, "jitter": {"eye": 0.3}, "cameras": [camera] * 3}
    for out in ("one", "two"):
        assert batch.run([job], tmp_path / out, progress=False).status == 0
    given = np.array(camera["camera_to_world"])
    moves = []
    for frame in range(3):
        got = [np.array(_records(tmp_path / out)[f"shaky/{frame:06d}"]["camera"]
                        ["camera_to_world"]) for out in ("one", "two")]
        assert np.array_equal(got[0], got[1])   # seeded
        assert np.array_equal(got[0][:3, :3], given[:3, :3])   # the axes kept
        move = np.linalg.norm(got[0][:3, 3] - given[:3, 3])
        assert 0 < move <= 0.3 + 1e-12
        moves.append(tuple(got[0][:3, 3]))
        npz = np.load(tmp_path / "one" / "shaky" / f"{frame:06d}.masks.npz")
        assert np.allclose(npz["camera_to_world"], got[0], atol=0)
    assert len(set(moves)) == 3   # each frame its own draw


@pytest.mark.parametrize("camera, message", [
    ({**LOOK_AT, "fx": 50.0}, "cameras[0].fx: given with eye: mixes the two camera forms"),
    ({"fx": 50.0, "fy": 50.0, "cx": 16.0, "camera_to_world": np.eye(4).tolist()},
     "cameras[0].cy: missing"),
    ({"fx": 50.0, "fy": 50.0, "cx": 16.0, "cy": 12.0,
      "camera_to_world": (2 * np.eye(4)).tolist()}, "cameras[0].camera_to_world: not rigid"),
    ({"fx": -1.0, "fy": 50.0, "cx": 16.0, "cy": 12.0, "camera_to_world": np.eye(4).tolist()},
     "cameras[0].fx"),
    ({"fx": 50.0, "fy": 50.0, "cx": 16.0, "cy": 12.0, "camera_to_world": np.eye(4).tolist(),
      "fov_y": 40.0}, "cameras[0].fx: given with fov_y"),
])
def test_a_bad_matrix_camera_is_refused_naming_the_key(camera, message):
    (job,) = check_jobs([{"name": "bad", "scene": str(SCENES / "cage.toml"),
                          "cameras": [camera]}])
    assert isinstance(job, JobError) and message in job.error, job


def test_path_keys_are_look_at_cameras():
    keys = [_scene_camera(), _scene_camera()]
    (job,) = check_jobs([{"name": "bad", "scene": str(SCENES / "cage.toml"),
                          "cameras": {"path": {"keys": keys, "frames": 3}}}])
    assert isinstance(job, JobError) and "cameras.path.keys[0]" in job.error, job
