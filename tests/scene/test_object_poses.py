"""Object poses and classes in scene files: `transform = { matrix = [[4x4]] }` (a similarity:
checked finite, affine, no shear, no mirror, one scale) places a mesh as the same Euler
transform does; the pose is the rigid part and the scale belongs to the model; objects of one
mesh file at one scale are one model; `category` defaults to the mesh file's stem, "background"
for planes, the name otherwise."""

from __future__ import annotations

import numpy as np
import pytest
from builders import SCENES, rotation

from shadowvol.scene import BACKGROUND, Object, SceneError
from shadowvol.scenefile import load_scene, save_scene

CAGE = str(SCENES / "meshes" / "cage.obj")


def _scene(tmp_path, objects: str):
    path = tmp_path / "s.toml"
    path.write_text('[camera]\neye = [0.0, 2.0, 6.0]\ntarget = [0.0, 0.0, 0.0]\n\n' + objects)
    return load_scene(path)


def _matrix(turn, t, scale=1.0) -> str:
    rows = [[*(scale * turn[i]).tolist(), t[i]] for i in range(3)] + [[0, 0, 0, 1]]
    return repr(rows)


def test_a_matrix_places_a_mesh_as_euler_angles_do(tmp_path):
    turn = rotation([0, 1, 0], 20.0)
    scene = _scene(tmp_path, f'''
[[objects]]
name = "euler"
type = "mesh"
path = "{CAGE}"
transform = {{ rotation = [0.0, 20.0, 0.0], translation = [0.5, 1.0, -2.0] }}

[[objects]]
name = "matrix"
type = "mesh"
path = "{CAGE}"
transform = {{ matrix = {_matrix(turn, [0.5, 1.0, -2.0])} }}

[[objects]]
name = "bigger"
type = "mesh"
path = "{CAGE}"
transform = {{ matrix = {_matrix(turn, [0.5, 1.0, -2.0], 1.5)} }}
''')
    euler, matrix, bigger = scene.objects
    assert np.allclose(euler.vertices, matrix.vertices, atol=1e-12)
    assert np.allclose(euler.pose, matrix.pose, atol=1e-12)
    assert euler.model_key == matrix.model_key != bigger.model_key   # one model at one scale
    assert np.allclose(bigger.pose, matrix.pose, atol=1e-12)         # the pose is rigid
    assert np.allclose(bigger.model_vertices(), 1.5 * matrix.model_vertices(), atol=1e-12)
    assert [o.label for o in scene.objects] == ["cage"] * 3


def test_categories_default_and_given(tmp_path):
    scene = _scene(tmp_path, f'''
[[objects]]
name = "floor"
type = "plane"

[[objects]]
name = "ball"
type = "sphere"
center = [0.0, 1.0, 0.0]
radius = 0.5

[[objects]]
name = "thing"
type = "mesh"
path = "{CAGE}"
category = "crate"

[[objects]]
name = "shelf"
type = "plane"
point = [0.0, 1.0, -1.0]
category = "shelf"
''')
    assert [o.label for o in scene.objects] == [BACKGROUND, "ball", "crate", "shelf"]
    assert scene.objects[1].category is None   # its name
    saved = tmp_path / "saved.toml"
    save_scene(scene, saved)
    assert [o.label for o in load_scene(saved).objects] == [BACKGROUND, "ball", "crate",
                                                           "shelf"]


@pytest.mark.parametrize("transform, message", [
    ("{ matrix = [[1, 0, 0, 0], [0, 2, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]] }",
     "objects[0].transform.matrix: not a pose: the 3x3 part is not a rotation times one scale"),
    ("{ matrix = [[1, 0.5, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]] }",
     "objects[0].transform.matrix: not a pose"),
    ("{ matrix = [[-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]] }",
     "objects[0].transform.matrix: not a pose: the 3x3 part is a mirror"),
    ("{ matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1]] }",
     "objects[0].transform.matrix: not rigid: the last row must be [0, 0, 0, 1]"),
    ("{ matrix = [[1, 0, 0, nan], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]] }",
     "objects[0].transform.matrix: non-finite number"),
    ("{ matrix = [[1, 0, 0], [0, 1, 0], [0, 0, 1]] }",
     "objects[0].transform.matrix: expected a 4x4 matrix"),
    ("{ matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], scale = 2 }",
     "objects[0].transform.scale: given with matrix"),
])
def test_a_bad_matrix_names_the_file_and_the_key(tmp_path, transform, message):
    with pytest.raises(SceneError) as caught:
        _scene(tmp_path, f'[[objects]]\ntype = "box"\ntransform = {transform}\n')
    text = str(caught.value)
    assert "\n" not in text and str(tmp_path / "s.toml") in text and message in text, text


def test_a_bad_category_names_the_key(tmp_path):
    with pytest.raises(SceneError, match=r"objects\[0\]\.category: expected a class name"):
        _scene(tmp_path, '[[objects]]\ntype = "box"\ncategory = ""\n')


def test_an_object_pose_is_a_similarity():
    v, f = np.eye(3), [[0, 1, 2]]
    with pytest.raises(SceneError, match="pose: not a pose"):
        Object("o", v, f, pose=np.diag([1.0, 2.0, 1.0, 1.0]))
    pose = np.eye(4)
    pose[:3, :3] = 2 * rotation([1, 1, 0], 30.0)
    obj = Object("o", v @ pose[:3, :3].T, f, pose=pose)
    assert np.allclose(obj.model_vertices(), v, atol=1e-12)


def test_the_cli_names_the_file_and_the_key_of_a_bad_matrix(tmp_path):
    """`shadowvol render` of a scene whose transform matrix shears: exit 2, one line."""
    import subprocess
    import sys

    from builders import ROOT

    bad = tmp_path / "bad.toml"
    bad.write_text('[camera]\neye = [0.0, 2.0, 6.0]\ntarget = [0.0, 0.0, 0.0]\n\n'
                   '[[objects]]\ntype = "box"\ntransform = { matrix = [[1, 0.5, 0, 0], '
                   '[0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]] }\n')
    done = subprocess.run([sys.executable, "-m", "shadowvol", "render", str(bad), "-o",
                           str(tmp_path / "out.png")], capture_output=True, text=True,
                          cwd=tmp_path, env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"})
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert str(bad) in lines[0] and "objects[0].transform.matrix: not a pose" in lines[0]
