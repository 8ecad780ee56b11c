"""glTF/GLB nodes become objects: each its own name, material and object id, in the file's node
order, with its world transform (a child's composed with its parent's) applied."""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest
import trimesh

from raytrace.groundtruth import ground_truth
from shadowvol.cameras import calibration, project
from shadowvol.scenefile import load_scene, save_scene

SCENE = """
[image]
width = 96
height = 64
[camera]
eye = [0.0, 6.0, 7.0]
target = [0.0, 0.5, 0.0]
fov_y = 40.0
[[lights]]
type = "directional"
direction = [0.2, -1.0, -0.3]
[[objects]]
type = "plane"
name = "floor"
size = [12.0, 12.0]
[[objects]]
type = "mesh"
name = "toy"
path = "toy.glb"
transform = { translation = [0.0, 0.0, 0.5] }
"""

RED, GREEN = [255, 0, 0, 255], [0, 255, 0, 255]


def translation(x, y, z) -> np.ndarray:
    return trimesh.transformations.translation_matrix([x, y, z])


def write_toy(folder) -> dict[str, np.ndarray]:
    """toy.glb: `base` (a red box at x = −2), `ball` (a sphere at x = +2) and `child`, a child
    of `base` with its own transform (0.6 scale, 45° about y, moved 2.5 back): a green box.
    Returns each node's world centre (before the scene file's own transform)."""
    red = trimesh.visual.material.PBRMaterial(baseColorFactor=RED)
    green = trimesh.visual.material.PBRMaterial(baseColorFactor=GREEN)
    base = trimesh.creation.box(extents=[1, 1, 1])
    base.visual = trimesh.visual.TextureVisuals(material=red)
    child = trimesh.creation.box(extents=[1, 1, 1])
    child.visual = trimesh.visual.TextureVisuals(material=green)
    ball = trimesh.creation.icosphere(subdivisions=2, radius=0.6)
    toy = trimesh.Scene()
    at_base = translation(-2, 0.5, 0)
    own = (translation(0, 0, -2.5) @ trimesh.transformations.rotation_matrix(np.pi / 4, [0, 1, 0])
           @ np.diag([0.6, 0.6, 0.6, 1.0]))
    toy.add_geometry(base, node_name="base", geom_name="base", transform=at_base)
    toy.add_geometry(ball, node_name="ball", geom_name="ball", transform=translation(2, 0.6, 0))
    toy.add_geometry(child, node_name="child", geom_name="child", parent_node_name="base",
                     transform=own)
    (folder / "toy.glb").write_bytes(toy.export(file_type="glb"))
    return {"base": np.array([-2, 0.5, 0.0]), "ball": np.array([2, 0.6, 0.0]),
            "child": (at_base @ own @ [0, 0, 0, 1])[:3]}


def glb_node_names(path) -> list[str]:
    data = path.read_bytes()
    length = struct.unpack_from("<I", data, 12)[0]
    return [node["name"] for node in json.loads(data[20:20 + length])["nodes"]]


@pytest.fixture
def toy(tmp_path):
    centres = write_toy(tmp_path)
    (tmp_path / "scene.toml").write_text(SCENE)
    return tmp_path, centres


def test_each_node_is_an_object_in_the_files_order(toy):
    folder, centres = toy
    scene = load_scene(folder / "scene.toml")
    order = glb_node_names(folder / "toy.glb")
    assert sorted(order) == ["ball", "base", "child"]
    assert [o.name for o in scene.objects] == ["floor"] + [f"toy/{n}" for n in order]
    for obj in scene.objects[1:]:
        node = obj.name.split("/")[1]
        # the node's world transform and then the scene file's translation
        want = centres[node] + [0, 0, 0.5]
        np.testing.assert_allclose(obj.vertices.mean(axis=0), want, atol=1e-9)
    by_name = {o.name: o for o in scene.objects}
    np.testing.assert_allclose(by_name["toy/base"].material.diffuse, [1, 0, 0])
    np.testing.assert_allclose(by_name["toy/child"].material.diffuse, [0, 1, 0])
    # the child's 0.6 scale: its box is 0.6 wide
    extent = np.ptp(by_name["toy/child"].vertices[:, 1])
    assert extent == pytest.approx(0.6)


def test_three_nodes_give_three_ids_in_the_right_places(toy):
    folder, centres = toy
    scene = load_scene(folder / "scene.toml")
    truth = ground_truth(scene, ["object_id"], backend="numpy")
    ids = truth.object_id
    cal = calibration(scene)
    for k, obj in enumerate(scene.objects[1:], start=2):
        node = obj.name.split("/")[1]
        u, v = project(cal.K, cal.world_to_camera, (centres[node] + [0, 0, 0.5])[None])[0]
        # the centre is inside the object: what the camera sees there is the object's front,
        # so the pixel of the projected centre shows this object, and so do its 3x3 neighbours
        x, y = int(u), int(v)
        assert (ids[y - 1:y + 2, x - 1:x + 2] == k).all(), (node, ids[y - 1:y + 2, x - 1:x + 2])
        assert (ids == k).sum() > 30
    assert set(np.unique(ids)) == {0, 1, 2, 3, 4}


def test_an_explicit_material_applies_to_every_node(toy):
    folder, _ = toy
    text = SCENE.replace('path = "toy.glb"', 'path = "toy.glb"\nmaterial = { diffuse = [0.1, 0.2, 0.3] }')
    (folder / "explicit.toml").write_text(text)
    scene = load_scene(folder / "explicit.toml")
    for obj in scene.objects[1:]:
        np.testing.assert_allclose(obj.material.diffuse, [0.1, 0.2, 0.3])


def test_a_saved_scene_keeps_the_nodes_as_objects(toy, tmp_path):
    folder, _ = toy
    scene = load_scene(folder / "scene.toml")
    save_scene(scene, tmp_path / "saved.toml")
    again = load_scene(tmp_path / "saved.toml")
    assert [o.name for o in again.objects] == [o.name for o in scene.objects]
    for a, b in zip(again.objects, scene.objects):
        np.testing.assert_array_equal(a.vertices, b.vertices)
        np.testing.assert_allclose(a.material.diffuse, b.material.diffuse)


def test_a_single_node_file_stays_one_object_named_by_the_scene(tmp_path):
    tri = trimesh.Trimesh(vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0]], faces=[[0, 1, 2]],
                          process=False)
    one = trimesh.Scene()
    one.add_geometry(tri, node_name="only")
    one.export(tmp_path / "toy.glb")
    (tmp_path / "scene.toml").write_text(SCENE)
    scene = load_scene(tmp_path / "scene.toml")
    assert [o.name for o in scene.objects] == ["floor", "toy"]
