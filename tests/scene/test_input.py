"""Degenerate and hostile input, each with its documented result (docs/robustness.md).

Geometry that is legal but degenerate must give the same masks from both renderers (zero
mismatches farther than one pixel from a mask edge), and the result the table promises.  Input
that is not legal is refused with a message naming the file and the key (exit status 2).
Loading never executes code, and a mesh's external resources cannot reach outside its folder
or the network.
"""

from __future__ import annotations

import base64
import json
import socket
import struct

import numpy as np
import pytest

import raytrace
from shadowvol.cli.main import main as shadowvol_main
from shadowvol.compare.maskdiff import mask_report
from shadowvol.io import load_masks
from shadowvol.primitives import box, mesh, plane, sphere
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import (
    Camera,
    DirectionalLight,
    Material,
    Object,
    PointLight,
    Scene,
    SceneError,
)
from shadowvol.scenefile import load_scene

RED = Material(diffuse=[0.8, 0.2, 0.2])
SIZE = dict(width=96, height=72)


def interior(ctx, scene, methods=("auto", "zfail", "zpass")) -> dict[str, list[int]]:
    """Interior mismatches per method (coverage first, then each light), and the reference."""
    lit, cov = raytrace.shadow_masks(scene)
    out = {}
    with Renderer(scene, ctx) as r:
        for method in methods:
            res = r.render(method)
            out[method] = [row["interior"] for row in mask_report(res.lit, res.coverage,
                                                                  lit, cov)]
    return out, (lit, cov)


def agree(ctx, scene, methods=("auto", "zfail")):
    report, ref = interior(ctx, scene, methods)
    assert all(not any(v) for v in report.values()), report
    return ref


def scene_of(objects, lights, eye=(0.0, 3.0, 5.0), target=(0.0, 0.5, 0.0), near=0.05, fov=50):
    return Scene(camera=Camera(eye=list(eye), target=list(target), near=near, fov_y=fov),
                 objects=objects, lights=lights, **SIZE)


# ---- degenerate geometry ----------------------------------------------------------------------

def test_zero_area_and_collinear_triangles_are_invisible_and_cast_nothing(ctx):
    """Triangles with two equal corners, three equal corners or three collinear corners: no
    coverage, no shadow, in both renderers; a mesh of only such triangles loads."""
    degenerate = mesh("degenerate", [[0, 1, 0], [1, 1, 0], [2, 1, 0], [0, 1, 0], [0, 2, 1]],
                      [[0, 1, 2], [0, 3, 4], [0, 0, 0], [1, 1, 4]], RED)
    base = [plane("floor", size=[8, 8]), box("b", [1.5, 0.5, 0], [1, 1, 1], RED)]
    lights = [PointLight([0.5, 3.0, 0.2]), DirectionalLight([0.2, -1, -0.3])]
    with_it = agree(ctx, scene_of(base + [degenerate], lights))
    without = agree(ctx, scene_of(base, lights))
    for a, b in zip(with_it, without):
        np.testing.assert_array_equal(a, b)


def test_coplanar_overlapping_triangles_do_not_shadow_each_other(ctx):
    """A quad lying exactly on the floor, overlapping it, and a box casting across both: the
    coplanar copy shadows nothing (it touches each shadow segment only at its start), and the
    box's shadow is the same on both."""
    decal = plane("decal", point=[0.3, 0.0, 0.2], size=[3, 2], material=RED)
    floor = plane("floor", size=[8, 8])
    lights = [PointLight([1.0, 3.0, 1.0]), DirectionalLight([0.4, -1, -0.2])]
    scene = scene_of([floor, decal, box("b", [-0.5, 0.5, -0.5], [1, 1, 1])], lights)
    lit, cov = agree(ctx, scene)
    alone = scene_of([floor, box("b", [-0.5, 0.5, -0.5], [1, 1, 1])], lights)
    np.testing.assert_array_equal(lit, raytrace.shadow_masks(alone)[0])


def test_a_light_exactly_on_a_surface(ctx):
    """A point light on the floor's plane (exactly: y = 0): the floor is unlit (n·l = 0) and
    casts no shadow (its volume has no thickness); what stands on the floor is lit where it
    faces the light.  The second scene is the long property run's find: the light on the floor
    and touching an icosahedron, seen from above."""
    floor = plane("floor", size=[8, 8])
    scene = scene_of([floor, box("b", [1.0, 0.5, 0], [0.6, 1, 0.6], RED)],
                     [PointLight([0.0, 0.0, 0.0])])
    lit, cov = agree(ctx, scene)
    floor_only = raytrace.shadow_masks(scene.replace(objects=(floor,)))[1]
    assert not lit[0][floor_only & ~cov].any() and lit[0].any()
    found = Scene(camera=Camera(eye=[0, 0.5, 0], target=[0, 0, 0], up=[0, 0, 1], fov_y=30,
                                near=0.01),
                  objects=[plane("floor", size=[12, 12]),
                           sphere("ball", [0.25, 0, 0], 0.25, RED, subdivisions=0)],
                  lights=[PointLight([0, 0, 0])], width=64, height=48)
    lit, cov = agree(ctx, found)
    assert lit.any()


def test_a_light_inside_a_closed_object(ctx):
    """Everything outside the box is in its shadow; the box's outside faces the light's
    unlit side.  Nothing the camera sees is lit."""
    scene = scene_of([plane("floor", size=[8, 8]), box("b", [0, 1, 0], [1, 1, 1], RED)],
                     [PointLight([0.1, 1.1, 0.05])])
    lit, cov = agree(ctx, scene)
    assert cov.mean() > 0.3 and not lit.any()


@pytest.mark.parametrize("light_inside", [True, False])
def test_the_camera_inside_a_closed_object(ctx, light_inside):
    """The eye inside a room (a closed box seen from inside) with a pillar in it: with the light
    inside, the walls are lit but for the pillar's shadow; with the light outside, nothing is
    lit.  Both renderers agree with every method that is right here (z-pass counts from the
    eye, which is outside every volume but the room's own)."""
    room = box("room", [0, 1.5, 0], [6, 3, 6], Material(diffuse=[0.7, 0.7, 0.7]))
    pillar = box("pillar", [0.8, 1.0, -0.8], [0.5, 2.0, 0.5], RED)
    light = PointLight([-1.0, 2.5, 1.0] if light_inside else [0.0, 6.0, 0.0])
    scene = scene_of([room, pillar], [light], eye=(1.5, 1.6, 2.4), target=(-1, 1, -2), fov=70)
    lit, cov = agree(ctx, scene)
    assert cov.all()
    if light_inside:
        assert 0.3 < lit.mean() < 0.99
    else:
        assert not lit.any()


def test_the_near_plane_cutting_an_object_and_its_volume(ctx):
    """A near plane 0.6 deep that slices through a box and into its shadow volume."""
    scene = scene_of([plane("floor", size=[8, 8]), box("b", [0, 0.6, 1.2], [1, 1.2, 1], RED)],
                     [PointLight([0.2, 4, 1.0])], eye=(0.1, 0.8, 1.5), target=(0, 0, -2),
                     near=0.6)
    agree(ctx, scene)


# ---- input that is refused ---------------------------------------------------------------------

def test_a_mesh_with_no_triangles_is_refused(tmp_path):
    with pytest.raises(SceneError, match="faces: the mesh has no triangles"):
        Object("empty", np.zeros((3, 3)), np.zeros((0, 3), int))
    path = tmp_path / "empty.toml"
    path.write_text('[camera]\neye = [0, 1, 3]\ntarget = [0, 0, 0]\n'
                    '[[objects]]\ntype = "mesh"\nvertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\n'
                    'faces = []\n')
    with pytest.raises(SceneError, match=r"empty\.toml: objects\[0\]\.faces: the mesh has no"):
        load_scene(path)
    (tmp_path / "points.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")
    path.write_text('[camera]\neye = [0, 1, 3]\ntarget = [0, 0, 0]\n'
                    '[[objects]]\ntype = "mesh"\npath = "points.obj"\n')
    with pytest.raises(SceneError, match=r"objects\[0\]\.path: .*(no triangles|no geometry)"):
        load_scene(path)


@pytest.mark.parametrize("where, text, key", [
    ("inline vertex", 'vertices = [[0, 0, 0], [nan, 0, 0], [0, 1, 0]]\nfaces = [[0, 1, 2]]',
     r"objects\[0\]\.vertices: 1 non-finite vertices"),
    ("inline inf", 'vertices = [[0, 0, 0], [inf, 0, 0], [0, 1, 0]]\nfaces = [[0, 1, 2]]',
     r"objects\[0\]\.vertices: 1 non-finite vertices"),
    ("OBJ file", 'path = "bad.obj"', r"objects\[0\]\.path: .*bad\.obj: 1 vertices are NaN"),
])
def test_non_finite_vertices_are_refused_naming_file_and_key(tmp_path, capsys, where, text, key):
    (tmp_path / "bad.obj").write_text("v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n")
    path = tmp_path / "scene.toml"
    path.write_text('[camera]\neye = [0, 1, 3]\ntarget = [0, 0, 0]\n'
                    f'[[objects]]\ntype = "mesh"\n{text}\n')
    with pytest.raises(SceneError, match=r"scene\.toml: " + key):
        load_scene(path)
    code = shadowvol_main(["render", str(path), "-o", str(tmp_path / "x.png")])
    assert code == 2 and "scene.toml: objects[0]" in capsys.readouterr().err


def test_non_finite_light_and_camera_are_refused(tmp_path):
    path = tmp_path / "s.json"
    data = {"camera": {"eye": [0, 1, 3], "target": [0, 0, 0]},
            "lights": [{"type": "point", "position": [0, float("inf"), 0]}],
            "objects": [{"type": "box"}]}
    path.write_text(json.dumps(data))  # json writes Infinity, and Python's json reads it back
    with pytest.raises(SceneError, match=r"s\.json: lights\[0\]\.position: non-finite"):
        load_scene(path)
    data["lights"] = []
    data["camera"]["eye"] = [float("nan"), 1, 3]
    path.write_text(json.dumps(data))
    with pytest.raises(SceneError, match=r"s\.json: camera\.eye: non-finite"):
        load_scene(path)


# ---- strangers' files --------------------------------------------------------------------------

def gltf_triangle(uri: str) -> dict:
    """A one-triangle glTF whose vertex buffer lives in the external file `uri`."""
    return {"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
            "buffers": [{"uri": uri, "byteLength": 36}],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 0]}]}


TRIANGLE = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)


def gltf_scene(folder, uri: str):
    (folder / "m.gltf").write_text(json.dumps(gltf_triangle(uri)))
    path = folder / "scene.toml"
    path.write_text('[camera]\neye = [0, 1, 3]\ntarget = [0, 0, 0]\n'
                    '[[objects]]\ntype = "mesh"\npath = "m.gltf"\n')
    return path


def test_gltf_external_buffer_beside_the_mesh_loads(tmp_path):
    (tmp_path / "tri.bin").write_bytes(TRIANGLE)
    scene = load_scene(gltf_scene(tmp_path, "tri.bin"))
    assert len(scene.objects[0].faces) == 1
    data_uri = "data:application/octet-stream;base64," + base64.b64encode(TRIANGLE).decode()
    assert len(load_scene(gltf_scene(tmp_path, data_uri)).objects[0].faces) == 1


@pytest.mark.parametrize("uri", ["../outside.bin", "../../outside.bin", "/etc/passwd",
                                 "file:///etc/passwd"])
def test_gltf_external_buffer_cannot_leave_the_mesh_folder(tmp_path, uri):
    """A buffer URI reaching outside the mesh's folder is not followed: the scene is refused
    (SceneError naming the key), even though a valid buffer lies at that path."""
    (tmp_path / "outside.bin").write_bytes(TRIANGLE)
    inner = tmp_path / "a" / "b"
    inner.mkdir(parents=True)
    (tmp_path / "a" / "outside.bin").write_bytes(TRIANGLE)
    with pytest.raises(SceneError, match=r"objects\[0\]\.path: cannot parse mesh"):
        load_scene(gltf_scene(inner, uri))


def test_gltf_external_buffer_never_reaches_the_network(tmp_path, monkeypatch):
    attempts = []

    def no_network(self, address):
        attempts.append(address)
        raise OSError("network use in a test")

    monkeypatch.setattr(socket.socket, "connect", no_network)
    with pytest.raises(SceneError, match=r"objects\[0\]\.path: cannot parse mesh"):
        load_scene(gltf_scene(tmp_path, "http://127.0.0.1:9/tri.bin"))
    assert attempts == []


@pytest.mark.parametrize("suffix", [".npz", ".npy", ".pkl", ".dae", ".blend", ".py"])
def test_only_data_mesh_formats_are_read(tmp_path, suffix):
    (tmp_path / f"m{suffix}").write_bytes(b"anything")
    path = tmp_path / "scene.toml"
    path.write_text('[camera]\neye = [0, 1, 3]\ntarget = [0, 0, 0]\n'
                    f'[[objects]]\ntype = "mesh"\npath = "m{suffix}"\n')
    with pytest.raises(SceneError, match="unsupported mesh format"):
        load_scene(path)


def test_mask_files_are_never_unpickled(tmp_path):
    path = tmp_path / "evil.npz"
    np.savez(path, lit=np.array([object()], dtype=object), coverage=np.zeros((1, 1), bool))
    with pytest.raises(ValueError, match="allow_pickle"):
        load_masks(path)


def test_scene_files_are_parsed_as_data(tmp_path):
    """TOML and JSON are data: a string that looks like code stays a string (here: an unknown
    material name, refused with the key)."""
    path = tmp_path / "s.toml"
    path.write_text('[camera]\neye = [0, 1, 3]\ntarget = [0, 0, 0]\n'
                    '[[objects]]\ntype = "box"\nmaterial = "__import__(\'os\').system(\'x\')"\n')
    with pytest.raises(SceneError, match=r"objects\[0\]\.material: no material named"):
        load_scene(path)
