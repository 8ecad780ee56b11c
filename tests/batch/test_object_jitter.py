"""`jitter.objects` and `jitter.colors` (`shadowvol.batch.jitter`): seeded property tests of
what the jitter guarantees (boxes above the ground, no overlap the scene did not have, the
pose carried with the geometry, the background left alone), its determinism, the frame error
when nothing fits, and the job checks."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from shadowvol.batch import jitter
from shadowvol.batch.jobs import JobError, check_jobs
from shadowvol.primitives import Transform, box, plane, sphere
from shadowvol.scene import BACKGROUND, Camera, PointLight, Scene, SceneError

SEEDS = range(40)
SPEC = {"translation": 0.5, "rotation": 180.0, "scale": 0.3, "axis": "any"}


def _crowd() -> Scene:
    """A floor, three boxes side by side (two touching), a ball in a bowl (their boxes
    overlap in the scene as given), a turned crate."""
    objects = (plane("floor", size=(8.0, 8.0)),
               box("a", center=(-1.0, 0.25, 0.0), size=(0.5, 0.5, 0.5)),
               box("b", center=(-0.5, 0.25, 0.0), size=(0.5, 0.5, 0.5)),   # touches a
               box("c", center=(0.4, 0.3, 0.2), size=(0.3, 0.6, 0.4)),
               box("bowl", center=(1.2, 0.1, -0.5), size=(0.8, 0.2, 0.8)),
               sphere("ball", (1.2, 0.25, -0.5), 0.2, subdivisions=1),
               box("crate", size=(0.4, 0.3, 0.2),
                   transform=Transform(rotation=(0, 30, 0), translation=(0.0, 0.15, 1.0))))
    objects = (dataclasses.replace(objects[0], category=BACKGROUND),) + objects[1:]
    return Scene(camera=Camera(eye=[0, 3, 6], target=[0, 0, 0]), objects=objects,
                 lights=(PointLight([0, 4, 0]),), width=32, height=24)


def _box(obj) -> np.ndarray:
    return np.stack([obj.vertices.min(axis=0), obj.vertices.max(axis=0)])


def _overlap(a, b, gap) -> bool:
    return bool(np.all(a[0] < b[1] - gap) and np.all(b[0] < a[1] - gap))


def test_jittered_objects_stay_above_the_ground_and_apart():
    """Over 40 seeds x 3 frames of a crowded scene and a wild jitter: every frame made keeps
    the guarantees; a frame where an object finds no place in `TRIES` draws is a SceneError
    (allowed, but rare here, so the check is not vacuous)."""
    scene = _crowd()
    gap = scene.extent * jitter.GAP
    before = [_box(o) for o in scene.objects]
    ground = min(b[0, 1] for b in before)
    made = failed = 0
    for seed in SEEDS:
        for index in range(3):
            try:
                got = jitter.jittered_scene(scene, {"objects": SPEC}, seed, index)
            except SceneError as exc:
                assert str(exc).startswith("jitter.objects: object ")
                failed += 1
                continue
            made += 1
            again = jitter.jittered_scene(scene, {"objects": SPEC}, seed, index)
            after = [_box(o) for o in got.objects]
            assert got.objects[0] is scene.objects[0]   # the background stays
            moved = 0.0
            for k, (old, new) in enumerate(zip(scene.objects, got.objects)):
                assert np.array_equal(new.vertices, again.objects[k].vertices)   # seeded
                assert after[k][0, 1] >= ground - gap
                for j in range(len(after)):
                    if j != k and not _overlap(before[k], before[j], gap):
                        assert not _overlap(after[k], after[j], gap), (seed, index, k, j)
                # the pose carries the geometry: the model (unchanged), posed, is the object
                pose = np.eye(4) if new.pose is None else new.pose
                assert np.allclose(old.model_vertices() @ pose[:3, :3].T + pose[:3, 3],
                                   new.vertices, atol=1e-9)
                assert new.model_key == old.model_key
                moved += float(np.abs(new.vertices - old.vertices).max())
            assert moved > 0.1   # the jitter did something
    assert made >= 0.8 * (made + failed), (made, failed)


def test_an_analytic_sphere_moves_with_its_triangles():
    scene = _crowd()
    got = jitter.jittered_scene(scene, {"objects": SPEC}, 5, 0)
    ball = got.objects[5]
    assert np.allclose(np.linalg.norm(ball.vertices - ball.analytic.center, axis=1),
                       ball.analytic.radius, atol=1e-9)


def test_up_axis_turns_keep_heights_and_scales_are_in_range():
    scene = _crowd()
    scene = scene.replace(objects=scene.objects[:2] + scene.objects[3:])   # room to turn
    spec = {"rotation": 90.0, "scale": 0.2}
    for seed in SEEDS:
        got = jitter.jittered_scene(scene, {"objects": spec}, seed, 0)
        for old, new in zip(scene.objects[1:], got.objects[1:]):
            pose = new.pose if old.pose is None else new.pose @ np.linalg.inv(old.pose)
            scale = float(np.cbrt(np.linalg.det(pose[:3, :3])))
            assert 0.8 - 1e-12 <= scale <= 1.2 + 1e-12
            axis = pose[:3, :3] / scale
            assert np.allclose(axis[1], [0, 1, 0], atol=1e-12)   # turned about +y only


def test_colours_are_relative_and_seeded():
    scene = _crowd()
    for seed in SEEDS:
        got = jitter.jittered_scene(scene, {"colors": 0.25}, seed, 4)
        again = jitter.jittered_scene(scene, {"colors": 0.25}, seed, 4)
        for old, new, same in zip(scene.objects, got.objects, again.objects):
            factor = new.material.diffuse / old.material.diffuse
            assert np.all((factor >= 0.75) & (factor <= 1.25))
            assert np.allclose(new.material.ambient, old.material.ambient * factor)
            assert np.array_equal(new.material.diffuse, same.material.diffuse)
            assert np.array_equal(new.vertices, old.vertices)
    other = jitter.jittered_scene(scene, {"colors": 0.25}, 0, 5)
    assert not np.array_equal(other.objects[1].material.diffuse,
                              jitter.jittered_scene(scene, {"colors": 0.25}, 0, 4)
                              .objects[1].material.diffuse)


def test_a_frame_where_nothing_fits_fails_naming_the_object():
    """A box in a slot between two background walls 1e-6 wider than it: any turn hits them."""
    walls = [dataclasses.replace(box(f"wall {i}", center=(x, 0.5, 0.0), size=(0.1, 1.0, 2.0)),
                                 category=BACKGROUND) for i, x in enumerate((-0.55, 0.55))]
    slot = box("slotted", center=(0.0, 0.5, 0.0), size=(1.0 - 2e-6, 1.0, 1.0))
    scene = Scene(camera=Camera(eye=[0, 3, 6], target=[0, 0, 0]),
                  objects=(*walls, slot), lights=())
    with pytest.raises(SceneError, match=r"jitter\.objects: object 'slotted': none of 100"):
        jitter.jittered_scene(scene, {"objects": {"rotation": 45.0}}, 0, 0)


@pytest.mark.parametrize("value, message", [
    ({"objects": {"rotation": 200}}, "jitter.objects.rotation: must be a number from 0 to 180"),
    ({"objects": {"scale": 1.0}}, "jitter.objects.scale: must be a number from 0 to below 1"),
    ({"objects": {"translation": -1}}, "jitter.objects.translation: must be a number >= 0"),
    ({"objects": {"axis": "x"}}, "jitter.objects.axis: must be \"up\" or \"any\""),
    ({"objects": {"spin": 1}}, "jitter.objects.spin: unknown key"),
    ({"objects": 3}, "jitter.objects: expected"),
    ({"colors": 1.5}, "jitter.colors: must be a number from 0 to 1"),
    ({"colors": "red"}, "jitter.colors: must be a number from 0 to 1"),
])
def test_bad_jitter_is_a_job_error_naming_the_key(value, message):
    job = {"name": "j", "scene": "x.toml", "cameras": [{"eye": [0, 1, 3], "target": [0, 0, 0]}],
           "jitter": value}
    (got,) = check_jobs([job])
    assert isinstance(got, JobError) and message in got.error, got


def test_the_cli_names_the_job_line_and_the_key_of_a_bad_jitter(tmp_path):
    """Exit 2 and one line (the job file's line, the key, the problem), no traceback."""
    import json
    import subprocess
    import sys

    from builders import ROOT, SCENES

    job = {"name": "j", "scene": str(SCENES / "cage.toml"), "size": [8, 6],
           "cameras": [{"eye": [4.2, 3.4, 5.2], "target": [-0.6, 1.0, -0.8]}],
           "jitter": {"objects": {"rotation": 400}}}
    jobs = tmp_path / "jobs.jsonl"
    jobs.write_text(json.dumps(job) + "\n")
    done = subprocess.run([sys.executable, "-m", "shadowvol", "batch", str(jobs), "-o",
                           str(tmp_path / "out"), "--no-progress"], capture_output=True,
                          text=True, cwd=tmp_path, env={"PYTHONPATH": str(ROOT),
                                                        "PATH": "/usr/bin:/bin"})
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    lines = [line for line in done.stderr.splitlines()
             if "jitter.objects.rotation" in line]
    assert len(lines) == 1 and f"{jobs}:1" in lines[0] and "from 0 to 180" in lines[0], \
        done.stderr


def test_objects_jittered_past_float32_name_the_jitter(tmp_path):
    """A translation radius within the float32 range that moves an object near its edge out
    of it fails that frame naming `jitter.objects.translation` (was: the model's own
    `vertices`, no word of jitter)."""
    import json

    from builders import tiny_scene

    from shadowvol.scenefile import load_scene
    from shadowvol.scenefile_write import save_scene

    path = tmp_path / "far.json"
    save_scene(tiny_scene(), path)
    data = json.loads(path.read_text())
    data["objects"] = [o for o in data["objects"] if o["name"] == "A"]
    data["objects"][0]["vertices"] = [[x + 9.9e17, y, z]
                                      for x, y, z in data["objects"][0]["vertices"]]
    path.write_text(json.dumps(data))
    scene = load_scene(path)
    errors = []
    for index in range(8):
        try:
            jitter.jittered_scene(scene, {"objects": {"translation": 5e17}}, 0, index)
        except SceneError as exc:
            errors.append(str(exc))
    assert errors, "no frame left the float32 range: the test needs another seed"
    for error in errors:
        assert error.startswith("jitter.objects.translation: a radius of 5e+17 moved the "
                                "objects out of range: "), error
