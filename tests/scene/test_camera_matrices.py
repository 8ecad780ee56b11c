"""Cameras given by matrices in the scene model and the scene files: fx, fy, cx, cy and
camera_to_world instead of eye, target, up, fov_y (docs/CONVENTIONS.md, scenes/README.md).

Every bad matrix camera is refused with one line naming the file, the key and the problem
(exit status 2, both tools, no traceback); `save_scene` writes the camera back in the form it
was given, bit for bit; `Scene.replace` to a new size scales the intrinsics with the image.
"""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys

import numpy as np
import pytest
from builders import ROOT, cards_scene, off_centre

from shadowvol.cameras import calibration
from shadowvol.cli.main import main as shadowvol_main
from shadowvol.cli.raytrace import main as raytrace_main
from shadowvol.scene import Camera, SceneError
from shadowvol.scenefile import load_scene, save_scene

POSE = [[0.0, 0.0, 1.0, 6.0], [0.0, 1.0, 0.0, 1.0], [-1.0, 0.0, 0.0, 0.5], [0.0, 0.0, 0.0, 1.0]]
GOOD = {"fx": 70.0, "fy": 55.5, "cx": 20.25, "cy": 17.0, "camera_to_world": POSE}
OBJECTS = [{"type": "plane", "size": [8, 8]},
           {"type": "box", "center": [0, 1, 0], "size": [1, 1, 1]}]


def _scene(camera: dict, suffix: str, tmp_path):
    data = {"image": {"width": 48, "height": 36}, "camera": camera,
            "lights": [{"type": "point", "position": [1, 5, 2]}], "objects": OBJECTS}
    path = tmp_path / f"scene{suffix}"
    if suffix == ".json":
        path.write_text(json.dumps(data))
    else:
        save_scene_text(path, data)
    return path


def save_scene_text(path, data) -> None:
    """`data` as TOML written by hand (nan and inf are TOML, not JSON)."""
    def value(v):
        if isinstance(v, dict):
            return "{" + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + "}"
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, str) and v in ("nan", "inf"):
            return v
        return json.dumps(v)
    lines = [f"image = {value(data['image'])}", f"camera = {value(data['camera'])}"]
    for key in ("lights", "objects"):
        for table in data[key]:
            lines += [f"[[{key}]]"] + [f"{k} = {value(x)}" for k, x in table.items()]
    path.write_text("\n".join(lines) + "\n")


def test_a_matrix_camera_loads_as_given(tmp_path):
    for suffix in (".toml", ".json"):
        camera = load_scene(_scene(GOOD, suffix, tmp_path)).camera
        assert camera.matrix_form and camera.fov_y is None
        assert (camera.fx, camera.fy, camera.cx, camera.cy) == (70.0, 55.5, 20.25, 17.0)
        np.testing.assert_array_equal(camera.camera_to_world, POSE)
        np.testing.assert_array_equal(camera.eye, [6.0, 1.0, 0.5])
        np.testing.assert_array_equal(camera.up, [0.0, 1.0, 0.0])
        np.testing.assert_array_equal(camera.target, camera.eye - np.array(POSE)[:3, 2])


def _shear():
    m = np.array(POSE)
    m[0, 1] = 1e-3
    return m.tolist()


def _scaled():
    m = np.array(POSE)
    m[:3, :3] *= 2.0
    return m.tolist()


def _mirror():
    m = np.array(POSE)
    m[:3, 0] *= -1
    return m.tolist()


BAD = {
    "3x3": ({"camera_to_world": [row[:3] for row in POSE[:3]]}, "camera.camera_to_world",
            "expected a 4x4 matrix"),
    "ragged": ({"camera_to_world": POSE[:3] + [[0, 0, 1]]}, "camera.camera_to_world",
               "expected a 4x4 matrix"),
    "strings": ({"camera_to_world": [["1", 0, 0, 0]] + POSE[1:]}, "camera.camera_to_world",
                "expected a 4x4 matrix"),
    "scaled": ({"camera_to_world": _scaled()}, "camera.camera_to_world", "not orthonormal"),
    "sheared": ({"camera_to_world": _shear()}, "camera.camera_to_world", "not orthonormal"),
    "mirrored": ({"camera_to_world": _mirror()}, "camera.camera_to_world", "mirror"),
    "last row": ({"camera_to_world": POSE[:3] + [[0, 0, 0.5, 1]]}, "camera.camera_to_world",
                 "last row"),
    "nan": ({"camera_to_world": [["nan", 0, 1, 6]] + POSE[1:]}, "camera.camera_to_world",
            "non-finite"),
    "inf translation": ({"camera_to_world": [[0, 0, 1, "inf"]] + POSE[1:]},
                        "camera.camera_to_world", "non-finite"),
    "fx zero": ({"fx": 0}, "camera.fx", "must be > 0"),
    "fy negative": ({"fy": -55.5}, "camera.fy", "must be > 0"),
    "cx string": ({"cx": "20"}, "camera.cx", "expected a number"),
    "fx nan": ({"fx": "nan"}, "camera.fx", "non-finite"),
    "cy missing": ({"cy": None}, "camera.cy", "missing"),
    "pose missing": ({"camera_to_world": None}, "camera.camera_to_world", "missing"),
    "with eye": ({"eye": [6, 1, 0.5]}, "camera.fx", "mixes the two camera forms"),
    "with fov_y": ({"fov_y": 40}, "camera.fx", "mixes the two camera forms"),
    "eye and cx": ({"fx": None, "fy": None, "camera_to_world": None, "cy": None,
                    "eye": [0, 1, 5], "target": [0, 0, 0]}, "camera.cx", "mixes"),
}


def _non_finite(change: dict) -> bool:
    return any(v in ("nan", "inf") for v in json.dumps(change).split('"'))


@pytest.mark.parametrize("case, suffix", [(case, suffix) for case in sorted(BAD)
                                          for suffix in (".toml", ".json")
                                          if suffix == ".toml" or not _non_finite(BAD[case][0])])
def test_bad_matrix_cameras_are_refused_naming_file_and_key(tmp_path, capsys, case, suffix):
    change, key, problem = BAD[case]
    camera = {k: v for k, v in {**GOOD, **change}.items() if v is not None}
    path = _scene(camera, suffix, tmp_path)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert f"{path.name}: {key}: " in str(info.value)
    assert problem in str(info.value)
    for main, argv in ((shadowvol_main, ["render", str(path), "-o", str(tmp_path / "x.png")]),
                       (raytrace_main, ["masks", str(path), "-o", str(tmp_path / "x.npz")])):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and f"{key}: " in err and problem in err, err
        assert path.name in err


def test_refused_from_the_command_line_in_one_line(tmp_path):
    path = _scene({**GOOD, "camera_to_world": _scaled()}, ".toml", tmp_path)
    for tool in ("shadowvol", "raytrace"):
        command = ["masks", str(path), "-o", str(tmp_path / "out.npz")] if tool == "raytrace" \
            else ["render", str(path), "-o", str(tmp_path / "out.png")]
        run = subprocess.run([sys.executable, "-m", tool, *command],
                             capture_output=True, text=True, cwd=ROOT, timeout=120)
        assert run.returncode == 2, run.stderr
        lines = run.stderr.strip().splitlines()
        assert len(lines) == 1 and "Traceback" not in run.stderr, run.stderr
        assert "scene.toml" in lines[0] and "camera.camera_to_world: not rigid" in lines[0]


def test_a_camera_mixing_the_forms_in_python_is_refused():
    with pytest.raises(SceneError, match="eye: mixes"):
        Camera(eye=[0, 0, 1], **{**GOOD, "camera_to_world": np.array(POSE)})
    camera = Camera(**GOOD)
    with pytest.raises(SceneError, match="eye: mixes"):   # moving it by its look-at keys
        dataclasses.replace(camera, eye=np.zeros(3))
    assert Camera(**GOOD).translated([1, 2, 3]).eye.tolist() == [7.0, 3.0, 3.5]


@pytest.mark.parametrize("suffix", [".toml", ".json"])
def test_save_scene_writes_the_camera_in_the_form_given(tmp_path, suffix):
    scene = off_centre(cards_scene(width=50, height=30))
    path = tmp_path / f"s{suffix}"
    save_scene(scene, path)
    text = path.read_text()
    assert "camera_to_world" in text and "fov_y" not in text and '"eye"' not in text
    back = load_scene(path)
    for name in ("fx", "fy", "cx", "cy", "near"):
        assert getattr(back.camera, name) == getattr(scene.camera, name), name
    assert np.array_equal(back.camera.camera_to_world, scene.camera.camera_to_world)
    for a, b in zip(calibration(back), calibration(scene)):
        assert np.array_equal(a, b)
    look_at = cards_scene(width=50, height=30)
    save_scene(look_at, path)
    assert "fov_y" in path.read_text() and "camera_to_world" not in path.read_text()
    assert load_scene(path).camera.fov_y == look_at.camera.fov_y


def test_a_new_image_size_scales_the_intrinsics():
    scene = off_centre(cards_scene(width=50, height=30))
    c = scene.camera
    big = scene.replace(width=100, height=90)
    assert (big.camera.fx, big.camera.cx) == (c.fx * 2, c.cx * 2)
    assert (big.camera.fy, big.camera.cy) == (c.fy * 3, c.cy * 3)
    assert scene.replace(name="same").camera is c
    assert scene.replace(width=50).camera is c
    look_at = cards_scene(width=50, height=30)
    assert look_at.replace(width=100).camera is look_at.camera


def test_the_documented_matrix_camera_loads_and_is_calibrated_toml():
    """scenes/README.md's "Cameras by matrices" block is a real camera: the one of the example
    scene calibrated.toml, whose frame's K and camera_to_world are the file's numbers."""
    import tomllib

    text = (ROOT / "scenes" / "README.md").read_text()
    block = text.split("## Cameras by matrices\n", 1)[1].split("```toml\n", 1)[1]
    table = tomllib.loads(block.split("```", 1)[0])["camera"]
    scene = load_scene(ROOT / "scenes" / "calibrated.toml")
    documented = Camera(**table)
    for name in ("fx", "fy", "cx", "cy", "near"):
        assert getattr(documented, name) == getattr(scene.camera, name), name
    np.testing.assert_array_equal(documented.camera_to_world, scene.camera.camera_to_world)
    cal = calibration(scene)
    np.testing.assert_array_equal(cal.camera_to_world, table["camera_to_world"])
    assert cal.K.tolist() == [[table["fx"], 0, table["cx"]], [0, table["fy"], table["cy"]],
                              [0, 0, 1]]
