"""Every integer field of a scene file and of a batch job, at the integer extremes (past int64,
past float64, negative, zero) and at random: a Scene (or a checked job), or a SceneError naming
the key; never another exception (an OverflowError once became a traceback)."""

from __future__ import annotations

import copy

import pytest
from hypothesis import given
from hypothesis import strategies as st

from shadowvol.batch.jobs import check_jobs
from shadowvol.scene import SceneError
from shadowvol.scenefile import scene_from_dict

EXTREMES = [0, -1, 1, 2**31, 2**53 + 1, 2**63 - 1, 2**63, -2**63 - 1, 2**64, 10**30,
            10**400, -10**400]
SCENE = {
    "camera": {"eye": [0, 1, 5], "target": [0, 0, 0], "fov_y": 45, "near": 0.1},
    "image": {"width": 16, "height": 12},
    "render": {"max_depth": 2},
    "lights": [{"type": "point", "position": [0, 3, 0]},
               {"type": "rect", "center": [0, 3, 0], "normal": [0, -1, 0],
                "size": [1, 1], "samples": 4, "seed": 1}],
    "objects": [{"type": "mesh", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
                 "faces": [[0, 1, 2]]},
                {"type": "sphere", "center": [0, 0, 0], "radius": 1, "subdivisions": 1}],
}
# every integer the schema has (and integers where it wants a real number)
FIELDS = [("image", "width"), ("image", "height"), ("render", "max_depth"),
          ("lights", 1, "samples"), ("lights", 1, "seed"), ("objects", 1, "subdivisions"),
          ("objects", 0, "faces", 0, 2), ("objects", 0, "vertices", 1, 0),
          ("camera", "fov_y"), ("camera", "near"), ("objects", 1, "radius"),
          ("lights", 0, "position", 1), ("lights", 1, "size", 0)]


def _with(path, value) -> dict:
    data = copy.deepcopy(SCENE)
    node = data
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return data


def _loads_or_refuses(data, path) -> None:
    try:
        scene_from_dict(data)
    except SceneError as exc:
        assert "Traceback" not in str(exc) and "\n" not in str(exc)


@pytest.mark.parametrize("path", FIELDS, ids=lambda p: ".".join(map(str, p)))
@pytest.mark.parametrize("value", EXTREMES, ids=lambda v: str(v) if abs(v) < 10**20 else f"{v // abs(v)}e{len(str(abs(v))) - 1}")
def test_scene_integer_extremes(path, value):
    _loads_or_refuses(_with(path, value), path)


@given(path=st.sampled_from(FIELDS), value=st.integers(min_value=-2**80, max_value=2**80))
def test_scene_integers_at_random(path, value):
    _loads_or_refuses(_with(path, value), path)


JOB = {"name": "j", "scene": SCENE, "size": [16, 12], "seed": 1, "max_depth": 1,
       "renderer": "raytrace",
       "cameras": {"orbit": {"center": [0, 0, 0], "radius": 5, "frames": 2}}}
JOB_FIELDS = [("size", 0), ("size", 1), ("seed",), ("max_depth",),
              ("cameras", "orbit", "frames"), ("cameras", "orbit", "radius"),
              ("cameras", "orbit", "elevation")]


@pytest.mark.parametrize("path", JOB_FIELDS, ids=lambda p: ".".join(map(str, p)))
@pytest.mark.parametrize("value", EXTREMES, ids=lambda v: str(v) if abs(v) < 10**20 else f"{v // abs(v)}e{len(str(abs(v))) - 1}")
def test_job_integer_extremes(tmp_path, path, value):
    job = copy.deepcopy(JOB)
    job["scene"] = scene_from_dict(SCENE)
    node = job
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    checked = check_jobs([job], tmp_path)
    for one in checked:   # a checked job, or a JobError that says what is wrong in one line
        error = getattr(one, "error", None)
        assert error is None or ("\n" not in error and "Traceback" not in error)
