"""The scene model and scene files: what loads, and the error every bad input gets."""

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
import trimesh
from builders import SCENES

from shadowvol import primitives
from shadowvol.scene import Camera, Material, PointLight, Scene, SceneError, SpotLight
from shadowvol.scenefile import load_scene, scene_from_dict

MINIMAL = """
[image]
width = 32
height = 24

[camera]
eye = [0.0, 2.0, 5.0]
target = [0.0, 0.0, 0.0]

[[lights]]
type = "point"
position = [1.0, 4.0, 1.0]

[[objects]]
type = "sphere"
center = [0.0, 1.0, 0.0]
radius = 0.5
"""


def write(tmp_path: Path, text: str, name: str = "scene.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def error_of(tmp_path: Path, text: str, name: str = "scene.toml") -> SceneError:
    path = write(tmp_path, text, name)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    err = info.value
    assert err.file == str(path), "the error must name the file"
    return err


@pytest.mark.parametrize("path", sorted(SCENES.glob("*.toml")) + sorted(SCENES.glob("*.json")),
                         ids=lambda p: p.name)
def test_every_example_scene_loads(path):
    scene = load_scene(path)
    assert scene.objects and scene.width > 0
    for obj in scene.objects:
        assert obj.vertices.flags.writeable is False and obj.faces.flags.writeable is False


def test_minimal_scene_defaults(tmp_path):
    scene = load_scene(write(tmp_path, MINIMAL))
    assert (scene.width, scene.height) == (32, 24)
    assert scene.name == "scene"
    assert isinstance(scene.lights[0], PointLight)
    sphere = scene.objects[0]
    assert sphere.analytic is not None and sphere.analytic.radius == 0.5
    # The icosphere's vertices lie on the exact sphere.
    r = np.linalg.norm(sphere.vertices - [0, 1, 0], axis=1)
    np.testing.assert_allclose(r, 0.5, rtol=1e-12)


def test_json_has_the_same_schema(tmp_path):
    import tomllib
    data = tomllib.loads(MINIMAL)
    path = write(tmp_path, json.dumps(data), "scene.json")
    a, b = load_scene(path), load_scene(write(tmp_path, MINIMAL))
    np.testing.assert_array_equal(a.objects[0].vertices, b.objects[0].vertices)
    np.testing.assert_array_equal(a.camera.eye, b.camera.eye)


def test_scene_is_frozen():
    scene = scene_from_dict({"camera": {"eye": [0, 0, 5], "target": [0, 0, 0]},
                             "objects": [{"type": "box"}]})
    with pytest.raises(dataclasses.FrozenInstanceError):
        scene.width = 3
    with pytest.raises(ValueError):
        scene.objects[0].vertices[0, 0] = 1.0
    smaller = dataclasses.replace(scene, width=8, height=8)
    assert smaller.width == 8 and scene.width == 640


def test_transform_order_scale_rotate_translate():
    t = primitives.Transform(scale=[2, 1, 1], rotation=[0, 0, 90], translation=[0, 0, 3])
    # x scaled by 2 -> (2,0,0); rotated 90 deg about z -> (0,2,0); translated -> (0,2,3).
    np.testing.assert_allclose(t.points(np.array([[1.0, 0, 0]])), [[0, 2, 3]], atol=1e-12)


def test_plane_rectangle_and_its_exact_parallelogram():
    floor = primitives.plane("floor", point=[1, 0, 2], normal=[0, 1, 0], size=[4, 6])
    lo, hi = floor.vertices.min(axis=0), floor.vertices.max(axis=0)
    np.testing.assert_allclose(lo, [-1, 0, -1])
    np.testing.assert_allclose(hi, [3, 0, 5])
    exact = floor.analytic
    np.testing.assert_allclose(exact.normal, [0, 1, 0])
    assert np.isclose(np.linalg.norm(np.cross(exact.edge_u, exact.edge_v)), 24.0)
    # The two triangles face the same way as the parallelogram.
    tri = floor.triangles
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert np.all(n @ exact.normal > 0)


def test_mesh_seam_duplicates_load_as_they_are(tmp_path):
    # Two triangles sharing an edge, written with the shared vertices duplicated (as exporters
    # do along UV seams): the loader must not weld them.
    obj = ("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
           "f 1 2 3\nf 4 5 6\n")
    (tmp_path / "seam.obj").write_text(obj)
    scene = load_scene(write(tmp_path, MINIMAL + '\n[[objects]]\ntype = "mesh"\npath = "seam.obj"\n'))
    mesh = scene.objects[1]
    assert mesh.vertices.shape == (6, 3) and mesh.faces.tolist() == [[0, 1, 2], [3, 4, 5]]


def test_gltf_node_transforms_are_applied(tmp_path):
    tri = trimesh.Trimesh(vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0]], faces=[[0, 1, 2]],
                          process=False)
    gltf_scene = trimesh.Scene()
    moved = np.eye(4)
    moved[:3, 3] = [10, 0, 0]
    gltf_scene.add_geometry(tri, node_name="a", transform=moved)
    gltf_scene.export(tmp_path / "tri.glb")
    scene = load_scene(write(tmp_path, MINIMAL + '\n[[objects]]\ntype = "mesh"\npath = "tri.glb"\n'))
    np.testing.assert_allclose(np.sort(scene.objects[1].vertices[:, 0]), [10, 10, 11])


def test_mesh_transform_from_file(tmp_path):
    (tmp_path / "t.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    text = MINIMAL + ('\n[[objects]]\ntype = "mesh"\npath = "t.obj"\n'
                      'transform = { scale = 2.0, translation = [0.0, 0.0, -1.0] }\n')
    v = load_scene(write(tmp_path, text)).objects[1].vertices
    np.testing.assert_allclose(v, [[0, 0, -1], [2, 0, -1], [0, 2, -1]])


# --- bad input: every case names the file, the key and the problem -----------------------------

BAD_CASES = {
    "unknown top-level key": ("colour = 3\n" + MINIMAL, "colour", "unknown key"),
    "unknown key in an object": (MINIMAL + "colour = 3\n", "objects[0].colour", "unknown key"),
    "unknown camera key": (MINIMAL.replace("fov", "x").replace(
        "target = [0.0, 0.0, 0.0]", "target = [0.0, 0.0, 0.0]\nfocus = 2.0"),
        "camera.focus", "unknown key"),
    "wrong type": (MINIMAL.replace("radius = 0.5", 'radius = "big"'),
                   "objects[0].radius", "expected a number"),
    "vector of the wrong length": (MINIMAL.replace("eye = [0.0, 2.0, 5.0]", "eye = [0.0, 2.0]"),
                                   "camera.eye", "expected 3 numbers"),
    "non-finite number": (MINIMAL.replace("position = [1.0, 4.0, 1.0]",
                                          "position = [1.0, nan, 1.0]"),
                          "lights[0].position", "non-finite"),
    "infinite number": (MINIMAL.replace("radius = 0.5", "radius = inf"),
                        "objects[0].radius", "non-finite"),
    "zero-size image": (MINIMAL.replace("width = 32", "width = 0"), "image.width", "positive"),
    "eye == target": (MINIMAL.replace("eye = [0.0, 2.0, 5.0]", "eye = [0.0, 0.0, 0.0]"),
                      "camera.target", "same point"),
    "up parallel to view": (MINIMAL.replace("eye = [0.0, 2.0, 5.0]", "eye = [0.0, 5.0, 0.0]"),
                            "camera.up", "parallel"),
    "negative radius": (MINIMAL.replace("radius = 0.5", "radius = -1.0"),
                        "objects[0].radius", "> 0"),
    "unknown object type": (MINIMAL.replace('type = "sphere"', 'type = "torus"'),
                            "objects[0].type", "unknown object type"),
    "unknown light type": (MINIMAL.replace('type = "point"', 'type = "area"'),
                           "lights[0].type", "unknown light type"),
    "missing camera": (MINIMAL.replace("[camera]\neye = [0.0, 2.0, 5.0]\ntarget = [0.0, 0.0, 0.0]", ""),
                       "camera", "missing"),
    "undefined material": (MINIMAL + 'material = "gold"\n', "objects[0].material", "gold"),
    "bad material value": (MINIMAL + "material = { shininess = -3 }\n",
                           "objects[0].material.shininess", ">= 0"),
    "reflective and transparent over 1": (
        MINIMAL + "material = { reflectivity = 0.6, transparency = 0.6 }\n",
        "objects[0].material.reflectivity", "<= 1"),
    "spot cone out of range": (MINIMAL.replace(
        'type = "point"\nposition = [1.0, 4.0, 1.0]',
        'type = "spot"\nposition = [1.0, 4.0, 1.0]\ndirection = [0.0, -1.0, 0.0]\n'
        'cone_angle = 120.0'), "lights[0].cone_angle", "<= 90"),
    "zero light direction": (MINIMAL.replace(
        'type = "point"\nposition = [1.0, 4.0, 1.0]',
        'type = "directional"\ndirection = [0.0, 0.0, 0.0]'), "lights[0].direction", "non-zero"),
    "non-uniform sphere scale": (MINIMAL + "transform = { scale = [1.0, 2.0, 1.0] }\n",
                                 "objects[0].transform.scale", "uniform"),
    "zero plane size": (MINIMAL.replace('type = "sphere"\ncenter = [0.0, 1.0, 0.0]\nradius = 0.5',
                                        'type = "plane"\nsize = [0.0, 3.0]'),
                        "objects[0].size", "positive"),
    "no objects": ("objects = []\n[camera]\neye = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n",
                   "objects", "no objects"),
}


@pytest.mark.parametrize("case", sorted(BAD_CASES), ids=str)
def test_bad_scene_names_key_and_problem(tmp_path, case):
    text, key, problem = BAD_CASES[case]
    err = error_of(tmp_path, text)
    assert err.key == key, str(err)
    assert problem in err.problem, str(err)
    assert str(err).startswith(str(tmp_path / "scene.toml") + ": " + key)


def test_broken_toml(tmp_path):
    err = error_of(tmp_path, MINIMAL.replace("width = 32", "width = = 32"))
    assert "not valid TOML" in err.problem


def test_broken_json(tmp_path):
    err = error_of(tmp_path, "{\"camera\": ", "scene.json")
    assert "not valid JSON" in err.problem


def test_missing_scene_file(tmp_path):
    with pytest.raises(SceneError, match="cannot read the scene file"):
        load_scene(tmp_path / "nope.toml")


def test_missing_mesh_file(tmp_path):
    err = error_of(tmp_path, MINIMAL + '\n[[objects]]\ntype = "mesh"\npath = "gone.obj"\n')
    assert err.key == "objects[1].path" and "not found" in err.problem


def test_mesh_that_does_not_parse(tmp_path):
    (tmp_path / "bad.ply").write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 9\n"
                                       b"property float x\nend_header\n\x00\x01")
    err = error_of(tmp_path, MINIMAL + '\n[[objects]]\ntype = "mesh"\npath = "bad.ply"\n')
    assert err.key == "objects[1].path"
    assert "bad.ply" in err.problem


def test_mesh_with_nan_vertex(tmp_path):
    (tmp_path / "nan.obj").write_text("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n")
    err = error_of(tmp_path, MINIMAL + '\n[[objects]]\ntype = "mesh"\npath = "nan.obj"\n')
    assert err.key == "objects[1].path" and "NaN or infinite" in err.problem


def test_mesh_without_triangles(tmp_path):
    (tmp_path / "points.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")
    err = error_of(tmp_path, MINIMAL + '\n[[objects]]\ntype = "mesh"\npath = "points.obj"\n')
    assert err.key == "objects[1].path" and "no triangles" in err.problem


def test_unsupported_mesh_format(tmp_path):
    (tmp_path / "x.pkl").write_bytes(b"\x80\x04")
    err = error_of(tmp_path, MINIMAL + '\n[[objects]]\ntype = "mesh"\npath = "x.pkl"\n')
    assert "unsupported mesh format" in err.problem


def test_api_constructors_validate_too():
    with pytest.raises(SceneError, match="same point"):
        Camera(eye=[1, 1, 1], target=[1, 1, 1])
    with pytest.raises(SceneError, match="non-finite"):
        primitives.mesh("m", [[0, 0, 0], [1, 0, np.nan], [0, 1, 0]], [[0, 1, 2]])
    with pytest.raises(SceneError, match="index out of range"):
        primitives.mesh("m", [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 3]])
    with pytest.raises(SceneError, match="no triangles"):
        primitives.mesh("m", np.zeros((0, 3)), np.zeros((0, 3), int))
    with pytest.raises(SceneError, match="must be a positive whole number"):
        Scene(camera=Camera(eye=[0, 0, 5], target=[0, 0, 0]), objects=[primitives.box("b")],
              lights=[], width=0)
    with pytest.raises(SceneError, match="not a light"):
        Scene(camera=Camera(eye=[0, 0, 5], target=[0, 0, 0]), objects=[primitives.box("b")],
              lights=["sun"])
    spot = SpotLight(position=[0, 1, 0], direction=[0, -2, 0], cone_angle=60)
    np.testing.assert_allclose(spot.direction, [0, -1, 0])
    assert np.isclose(spot.cos_cutoff, 0.5)
    assert Material().ior == 1.5


def test_triangle_soup_concatenates_objects():
    scene = Scene(camera=Camera(eye=[0, 0, 5], target=[0, 0, 0]),
                  objects=[primitives.box("a"), primitives.plane("p")], lights=[])
    v, f, ids = scene.triangles()
    assert v.shape == (12, 3) and f.shape == (14, 3)
    assert ids.tolist() == [0] * 12 + [1] * 2
    np.testing.assert_array_equal(v[f[12:]], scene.objects[1].triangles)


def test_the_documented_example_loads():
    """scenes/README.md's complete example is a real scene (its mesh path is relative to scenes/)."""
    import tomllib
    text = (SCENES / "README.md").read_text()
    block = text.split("```toml\n", 1)[1].split("```", 1)[0]
    scene = scene_from_dict(tomllib.loads(block), base_dir=SCENES)
    assert [type(o).__name__ for o in scene.lights] == ["PointLight", "DirectionalLight",
                                                        "SpotLight"]
    assert [o.name for o in scene.objects][:1] == ["floor"]
    assert len(scene.objects) == 5 and scene.objects[3].faces.shape == (984, 3)
    cage, turned = scene.objects[3:]   # two instances of one model (its scale differs: not)
    assert [cage.label, turned.label] == ["cage", "cage"]
    assert turned.pose.tolist() == [[0, 0, 1, 2], [0, 1, 0, 0], [-1, 0, 0, 0], [0, 0, 0, 1]]
    assert cage.model_key != turned.model_key   # the first is at scale 0.5


def test_save_scene_round_trip(tmp_path):
    from shadowvol.scenefile import save_scene
    original = load_scene(SCENES / "whitted.toml")
    save_scene(original, tmp_path / "copy.json")
    copy = load_scene(tmp_path / "copy.json")
    assert len(copy.objects) == len(original.objects)
    for a, b in zip(original.objects, copy.objects):
        np.testing.assert_array_equal(a.triangles, b.triangles)
        np.testing.assert_array_equal(a.material.diffuse, b.material.diffuse)
    for a, b in zip(original.lights, copy.lights):
        assert type(a) is type(b)
        np.testing.assert_array_equal(a.radiance, b.radiance)
    np.testing.assert_array_equal(original.camera.eye, copy.camera.eye)
    assert (copy.width, copy.height, copy.max_depth) == (original.width, original.height,
                                                         original.max_depth)


def test_inline_mesh_needs_path_or_vertices(tmp_path):
    err = error_of(tmp_path, MINIMAL + '\n[[objects]]\ntype = "mesh"\nname = "m"\n')
    assert err.key == "objects[1]" and "either `path`" in err.problem
    err = error_of(tmp_path, MINIMAL + '\n[[objects]]\ntype = "mesh"\n'
                                       'vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]\n'
                                       'faces = [[0, 1, 2]]\n')
    assert err.key == "objects[1].faces" and "out of range" in err.problem


def test_error_without_a_key_reads_cleanly(tmp_path):
    with pytest.raises(SceneError) as info:
        load_scene(tmp_path / "nope.toml")
    assert str(info.value).startswith(f"{tmp_path / 'nope.toml'}: cannot read the scene file")


def test_written_files_get_the_usual_mode(tmp_path):
    import os

    from shadowvol.io import save_png
    save_png(tmp_path / "a.png", np.zeros((2, 2, 3)))
    umask = os.umask(0)
    os.umask(umask)
    assert (tmp_path / "a.png").stat().st_mode & 0o777 == 0o666 & ~umask
    assert [p.name for p in tmp_path.iterdir()] == ["a.png"], "no temporary file left behind"
