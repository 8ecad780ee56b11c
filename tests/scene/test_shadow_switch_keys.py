"""The shadow switches as scene-file keys (scenes/README.md): an object's `cast_shadows` and
`receive_shadows`, a light's `shadows` (an area light's samples inherit it), true by default;
saved only where false, read back the same from TOML and JSON; anything but true or false is
one line naming the file and the key, exit 2 from both tools, no traceback."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from builders import overlapping_shadows, switched

from shadowvol.scene import Object, PointLight, SceneError
from shadowvol.scenefile import load_scene, save_scene
from shadowvol.scenefile_write import scene_to_dict

SCENE = """\
[camera]
eye = [0, 3, 6]
target = [0, 0, 0]

[[lights]]
type = "point"
position = [1, 4, 1]
shadows = false

[[lights]]
type = "disk"
center = [0, 4, 0]
normal = [0, -1, 0]
radius = 0.5
samples = 4
shadows = false

[[lights]]
type = "directional"
direction = [0, -1, 0]

[[objects]]
type = "plane"
receive_shadows = false

[[objects]]
type = "box"
cast_shadows = false
receive_shadows = true

[[objects]]
type = "sphere"
center = [1, 1, 0]
radius = 0.5
"""


def switches(scene):
    return ([(o.cast_shadows, o.receive_shadows) for o in scene.objects],
            [lt.shadows for lt in scene.lights])


def test_the_keys_in_toml_and_json(tmp_path):
    toml = tmp_path / "s.toml"
    toml.write_text(SCENE)
    scene = load_scene(toml)
    assert switches(scene) == ([(True, False), (False, True), (True, True)],
                               [False, False, True])
    assert all(not sample.shadows for sample in scene.lights[1].hard)
    for suffix in (".toml", ".json"):
        saved = tmp_path / f"saved{suffix}"
        save_scene(scene, saved)
        assert switches(load_scene(saved)) == switches(scene)


def test_python_defaults_and_files_without_switches_stay_as_they_were():
    scene = overlapping_shadows()
    assert switches(scene) == ([(True, True)] * 4, [True] * 4)
    text = json.dumps(scene_to_dict(scene))
    assert "shadows" not in text   # nothing switched: no key written
    data = scene_to_dict(switched(scene, cast=[1], receive=[2], lights=[0]))
    assert data["objects"][1]["cast_shadows"] is False
    assert data["objects"][2]["receive_shadows"] is False
    assert data["lights"][0]["shadows"] is False
    assert "cast_shadows" not in data["objects"][0] and "shadows" not in data["lights"][1]


@pytest.mark.parametrize("line, key, value", [
    ("cast_shadows = 1", "objects[1].cast_shadows", "1"),
    ('receive_shadows = "no"', "objects[1].receive_shadows", "'no'"),
    ("shadow = false", "objects[1].shadow", None)])
def test_bad_object_switches_name_the_file_and_key(tmp_path, line, key, value):
    bad = tmp_path / "bad.toml"
    bad.write_text(SCENE.replace("cast_shadows = false\nreceive_shadows = true", line))
    with pytest.raises(SceneError) as err:
        load_scene(bad)
    message = str(err.value)
    assert "\n" not in message and "bad.toml" in message and key in message
    if value is not None:
        assert message.endswith(f"expected true or false, got {value}")
    else:
        assert "unknown key" in message


def test_bad_light_switch_and_python_values():
    from shadowvol.scenefile import light_from_dict

    with pytest.raises(SceneError, match=r"^lights\[0\]\.shadows: expected true or false"):
        light_from_dict({"type": "point", "position": [0, 1, 0], "shadows": 0}, "lights[0]")
    with pytest.raises(SceneError, match="shadows: expected true or false"):
        PointLight([0, 1, 0], shadows="false")
    with pytest.raises(SceneError, match="cast_shadows: expected true or false"):
        Object("b", [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], cast_shadows=None)


@pytest.mark.parametrize("command", [["shadowvol", "render"], ["raytrace", "masks"]])
def test_both_tools_exit_2_with_one_line(tmp_path, command):
    bad = tmp_path / "bad.toml"
    bad.write_text(SCENE.replace("shadows = false", "shadows = 0", 1))
    out = tmp_path / "out.npz" if command[1] == "masks" else tmp_path / "out.png"
    done = subprocess.run([sys.executable, "-m", command[0], command[1], str(bad), "-o",
                           str(out)], capture_output=True, text=True, cwd=tmp_path)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2, done.stderr
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert "bad.toml" in lines[0] and "lights[0].shadows: expected true or false" in lines[0]
    assert not out.exists()
