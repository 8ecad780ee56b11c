"""A batch worker's ray-traced frames share the masks' backend (`raytrace.masks.scene_backend`)
while it stays valid: the same objects and the same eye (the backend's frame origin).  Every
frame's arrays equal a fresh build's."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
from builders import SCENES

import raytrace
from shadowvol.batch.sources import SOURCES
from shadowvol.scene import Camera, PointLight
from shadowvol.scenefile import load_scene

TRUTH = ["depth", "object_id", "casters"]


def _frame(worker, scene, camera, lights, truth=TRUTH):
    wanted = ("lit", "coverage", *truth)
    got = SOURCES["raytrace"].arrays(worker, None, scene, camera, lights, wanted, truth)
    fresh = raytrace.ground_truth(scene.replace(camera=camera, lights=lights), outputs=truth)
    for name in ("lit", "coverage", *truth):
        np.testing.assert_array_equal(got[name], getattr(fresh, name), err_msg=name)
    return worker.mask_tracer[2]


def test_frames_from_one_eye_share_the_backend_and_a_new_eye_or_object_gets_its_own():
    scene = load_scene(SCENES / "stack.toml").replace(width=40, height=30)
    worker = SimpleNamespace(mask_tracer=None)
    eye = [4.0, 5.0, 6.0]
    first = _frame(worker, scene, Camera(eye=eye, target=[0.0, 0.3, 0.0], fov_y=40.0),
                   scene.lights)
    # the same eye, another target and another light: the same backend
    assert _frame(worker, scene, Camera(eye=eye, target=[0.5, 0.0, 0.2], fov_y=35.0),
                  (PointLight([1.0, 4.0, 1.0]),)) is first
    assert _frame(worker, scene, Camera(eye=eye, target=[0.5, 0.0, 0.2], fov_y=35.0),
                  scene.lights, truth=[]) is first   # the masks alone too
    # another eye: another frame origin, another backend
    moved_eye = _frame(worker, scene, Camera(eye=[-5.0, 4.0, 3.0], target=[0.0, 0.3, 0.0],
                                             fov_y=40.0), scene.lights)
    assert moved_eye is not first
    # an object moved (a jittered frame's objects are new ones): another backend
    moved = dataclasses.replace(scene.objects[1], vertices=scene.objects[1].vertices + 0.25)
    edited = scene.replace(objects=[scene.objects[0], moved, *scene.objects[2:]])
    assert _frame(worker, edited, Camera(eye=[-5.0, 4.0, 3.0], target=[0.0, 0.3, 0.0],
                                         fov_y=40.0), scene.lights) is not moved_eye
