"""Hostile or careless scene and mesh files (issue 10, item 3): each is refused before any
harm, with one line `FILE: KEY: problem` naming the real problem, exit status 2 from the CLI
(docs/robustness.md, "Input that is refused").  Nothing here needs GL.
"""

from __future__ import annotations

import base64
import json
import os
import struct
import threading

import numpy as np
import pytest

from shadowvol import scenefile
from shadowvol.cli.main import main as shadowvol_main
from shadowvol.cli.raytrace import main as raytrace_main
from shadowvol.primitives import Transform, mesh
from shadowvol.scene import MAX_MAGNITUDE, Camera, PointLight, SceneError
from shadowvol.scenefile import load_scene

CAMERA = {"eye": [0, 1, 3], "target": [0, 0, 0]}
TRIANGLE = {"type": "mesh", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "faces": [[0, 1, 2]]}


def scene_json(tmp_path, data=None, *, text=None, name="s.json"):
    path = tmp_path / name
    path.write_text(text if text is not None else json.dumps(data))
    return path


def refused(path, match: str, **kwargs) -> SceneError:
    """load_scene(path) raises a one-line SceneError naming the file and matching `match`."""
    with pytest.raises(SceneError, match=match) as info:
        load_scene(path, **kwargs)
    message = str(info.value)
    assert "\n" not in message and message.startswith(str(path)), message
    return info.value


def with_mesh(tmp_path, name: str, content: bytes):
    (tmp_path / name).write_bytes(content)
    return scene_json(tmp_path, {"camera": CAMERA,
                                 "objects": [{"type": "mesh", "path": name}]})


# ---- what is read at all ------------------------------------------------------------------------

def test_a_fifo_is_refused_without_waiting_for_a_writer(tmp_path):
    fifo = tmp_path / "s.json"
    os.mkfifo(fifo)
    done = []
    worker = threading.Thread(target=lambda: done.append(pytest.raises(SceneError, load_scene,
                                                                         fifo)), daemon=True)
    worker.start()
    worker.join(5.0)
    assert done, "load_scene blocked on a FIFO"
    assert "a FIFO (named pipe), not a regular file" in str(done[0].value)


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/null"])
def test_a_device_is_refused_unread(tmp_path, device):
    link = tmp_path / "s.json"
    link.symlink_to(device)
    refused(link, "the scene file is a character device, not a regular file")


def test_a_directory_is_refused(tmp_path):
    (tmp_path / "d.toml").mkdir()
    refused(tmp_path / "d.toml", "is a directory|Is a directory")


def test_a_scene_file_over_the_limit_is_refused_before_reading(tmp_path):
    path = scene_json(tmp_path, {"camera": CAMERA, "objects": [TRIANGLE]})
    load_scene(path, max_bytes=path.stat().st_size)  # at the limit: read
    refused(path, r"the scene file is \d+ bytes, more than the limit of 100: not read",
            max_bytes=100)


def test_a_sparse_mesh_over_the_limit_is_refused_before_reading(tmp_path):
    big = tmp_path / "big.obj"
    with open(big, "wb") as f:  # 2 GB, sparse: nothing is written, and nothing must be read
        f.truncate(2 << 30)
    path = scene_json(tmp_path, {"camera": CAMERA, "objects": [{"type": "mesh",
                                                                "path": "big.obj"}]})
    err = refused(path, r"objects\[0\]\.path: .*big\.obj is 2147483648 bytes, more than the "
                        r"limit of 1073741824")
    assert err.key == "objects[0].path"
    refused(path, r"more than the limit of 1000: not read", max_mesh_bytes=1000)


def test_a_mesh_path_to_a_device_is_refused(tmp_path):
    (tmp_path / "zero.obj").symlink_to("/dev/zero")
    path = scene_json(tmp_path, {"camera": CAMERA, "objects": [{"type": "mesh",
                                                                "path": "zero.obj"}]})
    refused(path, r"objects\[0\]\.path: .*zero\.obj is a character device")


# ---- the shape of the data ----------------------------------------------------------------------

@pytest.mark.parametrize("depth", [20, 600, 5000])
@pytest.mark.parametrize("suffix", [".json", ".toml"])
def test_deep_nesting_is_refused(tmp_path, depth, suffix):
    value = "[" * depth + "1" + "]" * depth
    text = (json.dumps({"camera": CAMERA, "objects": [TRIANGLE]})[:-1] + f', "name": {value}}}'
            if suffix == ".json" else
            f'name = {value}\n[camera]\neye = [0, 1, 3]\ntarget = [0, 0, 0]\n')
    path = scene_json(tmp_path, text=text, name="deep" + suffix)
    refused(path, r"nested more than 16 levels deep")


def test_a_list_over_the_length_limit_is_refused(tmp_path, monkeypatch):
    monkeypatch.setattr(scenefile, "MAX_LIST_LENGTH", 100)
    data = {"camera": CAMERA, "objects": [dict(TRIANGLE, faces=[[0, 1, 2]] * 101)]}
    refused(scene_json(tmp_path, data), r"objects\[0\]\.faces: a list of 101 items, more than "
                                        r"the limit of 100")


def test_the_length_limit_is_far_above_any_scene():
    assert scenefile.MAX_LIST_LENGTH >= 1 << 24 and scenefile.MAX_NESTING >= 8


def test_json_duplicate_keys_are_refused(tmp_path):
    text = ('{"camera": {"eye": [0, 1, 3], "eye": [0, 9, 3], "target": [0, 0, 0]}, '
            '"objects": [{"type": "box"}]}')
    refused(scene_json(tmp_path, text=text), r"s\.json: camera\.eye: duplicate key")
    text = '{"camera": {"eye": [0, 1, 3], "target": [0, 0, 0]}, "objects": [], "objects": []}'
    refused(scene_json(tmp_path, text=text), r"s\.json: objects: duplicate key")


# ---- numbers ------------------------------------------------------------------------------------

@pytest.mark.parametrize("where, value, key", [
    ("light", {"lights": [{"type": "point", "position": [0, 1e300, 0]}]}, r"lights\[0\]\.position"),
    ("vertex", {"objects": [dict(TRIANGLE, vertices=[[0, 0, 0], [1e39, 0, 0], [0, 1, 0]])]},
     r"objects\[0\]\.vertices"),
    ("scale", {"objects": [{"type": "box", "transform": {"scale": 1e300}}]},
     r"objects\[0\]\.transform\.scale"),
    ("scaled vertices", {"objects": [dict(TRIANGLE, transform={"scale": 1e10},
                                          vertices=[[0, 0, 0], [1e10, 0, 0], [0, 1, 0]])]},
     r"objects\[0\]\.vertices"),
    ("eye", {"camera": {"eye": [0, 1, 1e19], "target": [0, 0, 0]}}, r"camera\.eye"),
])
def test_numbers_beyond_float32s_range_are_refused(tmp_path, where, value, key):
    data = {"camera": CAMERA, "objects": [TRIANGLE], **value}
    refused(scene_json(tmp_path, data), key + r": .*beyond the float32 range")


@pytest.mark.parametrize("near", [1e-38, 1e-300])
def test_a_near_plane_too_small_for_float32_is_refused(tmp_path, near):
    data = {"camera": dict(CAMERA, near=near), "objects": [TRIANGLE]}
    refused(scene_json(tmp_path, data), r"camera\.near: .* too small for float32")


def test_a_large_world_is_not_an_error(tmp_path):
    """1e9 from the origin, a ground 1e12 wide, a near plane of 1e-9: all accepted."""
    far = [[1e9, 0, 1e9], [1e9 + 1, 0, 1e9], [1e9, 1, 1e9]]
    data = {"camera": {"eye": [1e9, 1, 1e9 + 3], "target": [1e9, 0, 1e9], "near": 1e-9},
            "lights": [{"type": "point", "position": [1e9, 5, 1e9]}],
            "objects": [dict(TRIANGLE, vertices=far),
                        {"type": "plane", "point": [1e9, 0, 1e9], "size": [1e12, 1e12]}]}
    scene = load_scene(scene_json(tmp_path, data))
    assert scene.objects[1].vertices.max() == pytest.approx(5e11 + 1e9)
    assert mesh("m", far, [[0, 1, 2]], transform=Transform(scale=1e8)).vertices.max() > 1e17


# ---- strict types -------------------------------------------------------------------------------

@pytest.mark.parametrize("value, key", [
    ({"camera": {"eye": ["0", 1, 3], "target": [0, 0, 0]}}, r"camera\.eye: expected 3 numbers"),
    ({"camera": {"eye": [True, 1, 3], "target": [0, 0, 0]}}, r"camera\.eye: expected 3 numbers"),
    ({"lights": [{"type": "point", "position": [0, 1, False]}]}, r"lights\[0\]\.position"),
    ({"objects": [dict(TRIANGLE, vertices=[[0, 0, 0], [1, "0", 0], [0, 1, 0]])]},
     r"objects\[0\]\.vertices\[1\]: expected \[x, y, z\] numbers"),
    ({"objects": [dict(TRIANGLE, vertices=[[0, 0, 0], [1, True, 0], [0, 1, 0]])]},
     r"objects\[0\]\.vertices\[1\]: expected"),
    ({"objects": [dict(TRIANGLE, faces=[[0, True, 2]])]},
     r"objects\[0\]\.faces\[0\]: expected \[i, j, k\] whole numbers"),
    ({"objects": [dict(TRIANGLE, faces=[[0, "1", 2]])]}, r"objects\[0\]\.faces\[0\]"),
    ({"objects": [dict(TRIANGLE, faces=[[0, 1.0, 2]])]}, r"objects\[0\]\.faces\[0\]"),
    ({"objects": [dict(TRIANGLE, faces=[[0, 1, 2, 0]])]}, r"objects\[0\]\.faces\[0\]"),
    ({"objects": [dict(TRIANGLE, faces="012")]}, r"objects\[0\]\.faces: expected"),
])
def test_strings_and_booleans_are_not_numbers(tmp_path, value, key):
    data = {"camera": CAMERA, "objects": [TRIANGLE], **value}
    refused(scene_json(tmp_path, data), key)


def test_the_api_is_strict_too():
    with pytest.raises(SceneError, match="position: expected 3 numbers"):
        PointLight(["1", 2, 3])
    with pytest.raises(SceneError, match="eye: expected 3 numbers"):
        Camera(eye=[True, 2, 3], target=[0, 0, 0])


# ---- meshes: the real problem named -------------------------------------------------------------

def test_obj_index_0_is_refused(tmp_path):
    path = with_mesh(tmp_path, "z.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 0 1 2\n")
    refused(path, r"objects\[0\]\.path: .*z\.obj: line 5: face index 0 \(OBJ indices start at 1\)")
    path = with_mesh(tmp_path, "z.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/0 2/1 3/1\n")
    refused(path, r"line 5: face index 0")
    # indices that merely contain a 0, and negative (relative) ones, are fine
    ok = with_mesh(tmp_path, "ok.obj", b"v 0 0 0\n" * 10 + b"v 1 0 0\nf 10 -1 -2\nf 1/10 2/10 3\n")
    assert len(load_scene(ok).objects[0].faces) == 2


def test_binary_data_in_an_obj_is_named(tmp_path):
    path = with_mesh(tmp_path, "b.obj", bytes(range(256)) * 8)
    refused(path, r"b\.obj holds binary data \(a NUL byte at 0\): an OBJ file is text")


def test_an_stl_that_is_neither_binary_nor_text_is_named(tmp_path):
    junk = b"\x01" * 80 + struct.pack("<I", 1000) + b"\x02" * 300
    refused(with_mesh(tmp_path, "j.stl", junk), r"j\.stl is neither a text STL .* nor a binary "
                                                r"STL \(its header says 1000 triangles, 50084 "
                                                r"bytes; the file has 384\)")
    refused(with_mesh(tmp_path, "short.stl", b"\x00" * 20), r"shorter than the 84-byte header")
    # a well-formed binary STL whose header begins with "solid" (exporters do this) loads
    tri = struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0)
    good = b"solid made by some exporter".ljust(80, b" ") + struct.pack("<I", 1) + tri
    assert len(load_scene(with_mesh(tmp_path, "g.stl", good)).objects[0].faces) == 1


def test_a_truncated_glb_is_named(tmp_path):
    import trimesh
    data = trimesh.exchange.gltf.export_glb(trimesh.Scene(trimesh.creation.box()))
    refused(with_mesh(tmp_path, "t.glb", data[:len(data) // 2]),
            rf"t\.glb is truncated or padded: its header says {len(data)} bytes, the file has "
            rf"{len(data) // 2}")
    refused(with_mesh(tmp_path, "n.glb", b"not a glb at all"), r"n\.glb is not a GLB file")
    assert len(load_scene(with_mesh(tmp_path, "ok.glb", data)).objects[0].faces) == 12


def test_a_truncated_gltf_is_named(tmp_path):
    text = json.dumps({"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}]})
    refused(with_mesh(tmp_path, "t.gltf", text[:25].encode()),
            r"t\.gltf is not valid glTF JSON \(truncated\?\)")


def tiny_gltf(nodes: list, **extra) -> bytes:
    """A glTF of one triangle (its buffer inline, base64) with these `nodes`, the scene's
    root node 0."""
    data = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    document = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
                "nodes": nodes, "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
                "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3,
                               "type": "VEC3", "max": [1, 1, 0], "min": [0, 0, 0]}],
                "bufferViews": [{"buffer": 0, "byteLength": 36}],
                "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,"
                             + base64.b64encode(data).decode()}], **extra}
    return json.dumps(document).encode()


@pytest.mark.parametrize("nodes, chain", [
    ([{"mesh": 0, "children": [0]}], "0 -> 0"),
    ([{"mesh": 0, "children": [1]}, {"children": [0]}], "0 -> 1 -> 0"),
    ([{"children": [1]}, {"mesh": 0, "children": [2]}, {"children": [0]}], "0 -> 1 -> 2 -> 0"),
])
def test_a_gltf_node_cycle_is_refused(tmp_path, nodes, chain):
    """trimesh walks a cycle until "Iteration limit exceeded!" (a bare ValueError) or drops
    it unsaid; glTF's nodes must form trees."""
    assert len(load_scene(with_mesh(tmp_path, "ok.gltf", tiny_gltf([{"mesh": 0}]))).objects) == 1
    refused(with_mesh(tmp_path, "c.gltf", tiny_gltf(nodes)),
            rf"objects\[0\]\.path: .*c\.gltf: nodes\[0\]: node 0 is its own ancestor \(the "
            rf"node graph has a cycle: {chain}\)$")


@pytest.mark.parametrize("nodes, problem", [
    ([{"mesh": 0, "children": [1]}, {}, {"children": [1]}], r"nodes\[2\]\.children: node 1 "
     r"is also a child of node 0 \(glTF nodes form trees\)"),
    ([{"mesh": 0, "children": [7]}], r"nodes\[0\]\.children: 7 is not a node index \(0\.\.0\)"),
])
def test_gltf_nodes_that_are_no_tree_are_refused(tmp_path, nodes, problem):
    refused(with_mesh(tmp_path, "c.gltf", tiny_gltf(nodes)), problem)


@pytest.mark.parametrize("change, problem", [
    ({"bufferViews": [{"buffer": 0, "byteLength": 48}]},
     r"bufferViews\[0\]: bytes 0\.\.48 reach past the end of buffers\[0\] \(36 bytes\)"),
    ({"bufferViews": [{"buffer": 0, "byteLength": 48}],
      "buffers": [{"byteLength": 48, "uri": "data:application/octet-stream;base64,"
                   + base64.b64encode(bytes(36)).decode()}]},
     r"bufferViews\[0\]: bytes 0\.\.48 reach past the end of buffers\[0\] \(36 bytes\)"),
    ({"bufferViews": [{"buffer": 0, "byteLength": 36, "byteStride": 24}]},
     r"accessors\[0\]: 3 VEC3 items of 12 bytes from byte 0 \(stride 24\) need 60 bytes, "
     r"bufferViews\[0\] has 36"),
    ({"bufferViews": [{"buffer": 0, "byteLength": 36, "byteStride": 0}]},
     r"bufferViews\[0\]\.byteStride: must be 4\.\.252 \(glTF\), got 0"),
    ({"bufferViews": [{"buffer": 3, "byteLength": 36}]},
     r"bufferViews\[0\]\.buffer: 3 is not a buffer index \(the file has 1 buffers\)"),
])
def test_a_gltf_buffer_view_or_accessor_past_its_data_is_named(tmp_path, change, problem):
    """trimesh checks these with bare asserts: the message was `AssertionError: ` alone."""
    refused(with_mesh(tmp_path, "b.gltf", tiny_gltf([{"mesh": 0}], **change)),
            rf"objects\[0\]\.path: .*b\.gltf: {problem}$")


def test_a_bare_assert_in_the_mesh_reader_is_named(tmp_path, monkeypatch):
    """Any other message-less failure of trimesh's names the statement that failed and where."""
    import trimesh

    def broken(*args, **kwargs):  # as a bare `assert` (pytest would rewrite one here)
        raise AssertionError()
    monkeypatch.setattr(trimesh, "load", broken)
    refused(with_mesh(tmp_path, "ok.gltf", tiny_gltf([{"mesh": 0}])),
            r"cannot parse mesh .*ok\.gltf: AssertionError: raise AssertionError\(\) "
            r"\(tests/scene/test_hostile_input\.py:\d+\)$")


def test_the_cli_refuses_a_gltf_cycle_in_one_line(tmp_path, capsys):
    path = with_mesh(tmp_path, "c.gltf", tiny_gltf([{"mesh": 0, "children": [1]},
                                                    {"children": [0]}]))
    for tool in (shadowvol_main, raytrace_main):
        args = ["render", str(path), "-o", str(tmp_path / "x.png")] if tool is shadowvol_main \
            else ["masks", str(path), "-o", str(tmp_path / "m.npz")]
        assert tool(args) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "has a cycle: 0 -> 1 -> 0" in err, err


def test_a_missing_optional_package_is_named(tmp_path, monkeypatch):
    import trimesh

    def load(*args, **kwargs):
        raise ModuleNotFoundError("No module named 'fancy_loader'", name="fancy_loader")

    monkeypatch.setattr(trimesh, "load", load)
    path = with_mesh(tmp_path, "m.ply", b"ply\nformat ascii 1.0\nend_header\n")
    refused(path, r"objects\[0\]\.path: reading .*m\.ply needs the Python package "
                  r"'fancy_loader', which is not installed \(pip install fancy_loader\)")


# ---- messages -----------------------------------------------------------------------------------

def test_a_long_wrong_value_is_cut_short(tmp_path):
    data = {"camera": dict(CAMERA, eye=list(range(1_000_000))), "objects": [TRIANGLE]}
    err = refused(scene_json(tmp_path, data), r"camera\.eye: expected 3 numbers, got \[0, 1, 2")
    assert len(str(err)) < 400 and "(1000000 items)" in str(err)


def test_a_key_with_a_line_break_stays_on_one_line(tmp_path):
    data = {"camera": CAMERA, "objects": [TRIANGLE], "bad\nkey\x1b[31m": 1}
    err = refused(scene_json(tmp_path, data), r"unknown key")
    assert "bad\\nkey" in str(err) and "\x1b" not in str(err)


def test_the_cli_gives_one_line_and_status_2(tmp_path, capsys):
    fifo = tmp_path / "f.json"
    os.mkfifo(fifo)
    dup = scene_json(tmp_path, text='{"camera": {"eye": [0,1,3], "eye": [0,1,3], '
                                    '"target": [0,0,0]}, "objects": [{"type": "box"}]}')
    for path, what in [(fifo, "not a regular file"), (dup, "duplicate key")]:
        code = shadowvol_main(["render", str(path), "-o", str(tmp_path / "x.png")])
        err = capsys.readouterr().err
        assert code == 2 and what in err and err.count("\n") == 1, err
        assert err.startswith("error: ") and "Traceback" not in err


def test_max_magnitude_is_inside_float32():
    big = np.float32(MAX_MAGNITUDE)
    assert np.isfinite(big * big * np.float32(3)) and np.isfinite(np.float32(1) / np.float32(1e-18))


@pytest.mark.parametrize("light, missing", [('type = "point"', "position"),
                                            ('type = "directional"', "direction"),
                                            ('type = "spot"\nposition = [0, 1, 0]', "direction")])
def test_a_light_without_its_required_key(tmp_path, light, missing):
    path = tmp_path / "s.toml"
    path.write_text(f'[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\n[[lights]]\n{light}\n'
                    '[[objects]]\ntype = "box"\n')
    with pytest.raises(SceneError, match=rf"lights\[0\]\.{missing}: missing"):
        load_scene(path)
