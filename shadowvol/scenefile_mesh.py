"""The files a scene file names: meshes (OBJ, PLY, STL, OFF, glTF/GLB, read by trimesh) and
the bounded reading of any file the loader opens (`read_regular_file`, the scene file's too).

A mesh file's bytes are read once, under the size limit, and checked here for what trimesh would
misreport (`check_mesh_bytes`) before trimesh parses them; a glTF scene or multi-mesh file gives
one `MeshPart` per node instance, in the file's node order.
"""

from __future__ import annotations

import dataclasses
import io
import json
import os
import re
import stat
import struct
from pathlib import Path
from typing import NamedTuple

import numpy as np

from shadowvol.scene import Material, SceneError, shorten
from shadowvol.scenefile_gltf import check_layout, check_node_tree, gltf_document
from shadowvol.scenefile_texture import (
    Surface,
    gltf_surfaces,
    obj_materials,
    trimesh_uv,
    vertex_colours,
    warn_ignored,
)

MESH_FORMATS = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf")
MAX_MESH_FILE_BYTES = 1 << 30  # the size limit of each mesh file (`load_scene` takes others)
AMBIENT_SHARE = 0.125  # a file's base colour as ambient: the default Material's 0.1 / 0.8


def read_regular_file(path: Path, max_bytes: int, key: str = "", what: str | None = None
                      ) -> bytes:
    """The bytes of `path` if it is a regular file of at most `max_bytes`, else a SceneError
    under `key` saying what it is (naming it as `what`, default the path).  Opened without
    blocking (a FIFO would wait for a writer), checked with fstat on the open file, then read
    to at most max_bytes + 1 (a file that grows meanwhile is still caught)."""
    what = what or str(path)
    fd = _open_regular(path, max_bytes, key, what)
    with os.fdopen(fd, "rb") as f:
        data = f.read(max_bytes + 1)
    if len(data) > max_bytes:
        raise SceneError(key, f"{what} grew past {max_bytes} bytes while being read")
    return data


def check_regular_file(path: Path, key: str = "", what: str | None = None) -> None:
    """SceneError under `key` when `path` exists and is not a regular file (a FIFO, a device, a
    directory, a socket), found by stat alone: nothing is opened, so nothing can block.  A
    missing file passes (the reader says so when it opens it)."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return
    if not stat.S_ISREG(mode):
        raise SceneError(key, f"{what or path} is {_file_kind(mode)}, not a regular file: "
                              "not read")


def _open_regular(path: Path, max_bytes: int, key: str, what: str) -> int:
    """An fd open for reading on `path`, a regular file of at most `max_bytes` (see
    `read_regular_file`)."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise SceneError(key, f"cannot read {what}: {exc.strerror or exc}") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise SceneError(key, f"{what} is {_file_kind(st.st_mode)}, not a regular file: "
                                  "not read")
        if st.st_size > max_bytes:
            raise SceneError(key, f"{what} is {st.st_size} bytes, more than the limit of "
                                  f"{max_bytes}: not read")
        os.set_blocking(fd, True)
    except BaseException:
        os.close(fd)
        raise
    return fd


def _file_kind(mode: int) -> str:
    for test, name in ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "not a regular file"


class MeshPart(NamedTuple):
    """One mesh of a mesh file, in the file's own space with its node transform applied.

    node     : the node's (or geometry's) name in the file, None for a single-mesh file
    vertices : (n, 3) float64;  faces : (m, 3) int64, as stored (seam duplicates kept)
    diffuse  : (3,) float64, the part's glTF baseColorFactor or MTL Kd (linear RGB), or None
    texture, uv, colors : its base-colour texture, UVs and vertex colours, or None
                          (`scenefile_texture`)
    """

    node: str | None
    vertices: np.ndarray
    faces: np.ndarray
    diffuse: np.ndarray | None
    texture: object = None
    uv: np.ndarray | None = None
    colors: np.ndarray | None = None


def part_name(name: str, part: MeshPart, parts: int) -> str:
    """The object name of a part: the entry's name, then `/node` when the file has several."""
    return name if parts == 1 or part.node is None else f"{name}/{part.node}"


def part_material(material: Material, part: MeshPart, given: bool) -> Material:
    """The material of a part: the entry's when it names one (`given`), else the part's own
    base colour as its diffuse colour (and AMBIENT_SHARE of it as its ambient: the default
    material's ratio, so that a red part stays red in shadow), else the default; with the
    part's texture either way."""
    if not given and part.diffuse is not None:
        material = Material(diffuse=part.diffuse, ambient=AMBIENT_SHARE * part.diffuse)
    if part.texture is not None:
        material = dataclasses.replace(material, texture=part.texture)
    return material


def read_mesh(rel, key: str, base_dir: Path, max_bytes: int = MAX_MESH_FILE_BYTES
               ) -> list[MeshPart]:
    """The parts of a mesh file (a regular file of at most `max_bytes`): one for a single
    mesh, one per node instance for a glTF/GLB scene or a multi-mesh file, in the file's node
    order (`_node_order`), each with its node's transform applied."""
    import trimesh  # deferred: trimesh's import is slow and only meshes need it here

    if not isinstance(rel, str) or not rel:
        raise SceneError(key, f"expected a file path, got {shorten(rel)}")
    path = base_dir / rel
    if path.suffix.lower() not in MESH_FORMATS:
        raise SceneError(key, f"{shorten(rel)}: unsupported mesh format (use one of "
                              f"{', '.join(MESH_FORMATS)})")
    if not path.exists():
        raise SceneError(key, f"mesh file not found: {path}")
    # Read (bounded) and checked here first, so that what trimesh would misreport is named.
    data = read_regular_file(path, max_bytes, key)
    check_mesh_bytes(path, data, key)
    try:
        # parsed from the bytes checked above (the path is not opened again), and the files a
        # glTF names (buffers, images) read by `_Resolver`: regular files, bounded
        loaded = trimesh.load(io.BytesIO(data), file_type=path.suffix.lower()[1:],
                              resolver=_resolver(path, max_bytes, key), process=False)
    except SceneError:
        raise
    except ImportError as exc:  # an optional package of trimesh's, for this format
        raise SceneError(key, f"reading {path} needs the Python package {exc.name!r}, which is "
                              f"not installed (pip install {exc.name})") from None
    except Exception as exc:  # trimesh raises many types for malformed files
        raise SceneError(key, f"cannot parse mesh {path}: {type(exc).__name__}: "
                              f"{str(exc) or _failed_check(exc)}") from None
    surfaces = _surfaces(path, data, loaded, key)
    if isinstance(loaded, trimesh.Scene):
        if not loaded.geometry:
            raise SceneError(key, f"{path} holds no geometry")
        parts = _scene_parts(loaded, _node_order(path, data), surfaces)
    elif isinstance(loaded, trimesh.Trimesh):
        parts = [_part(None, loaded, None, surfaces.get(None))]
    else:
        parts = []
    parts = [p for p in parts if len(p.faces)]
    if not parts:
        raise SceneError(key, f"{path} holds no triangles")
    for part in parts:
        if not np.isfinite(part.vertices).all():
            bad = int((~np.isfinite(part.vertices).all(axis=1)).sum())
            raise SceneError(key, f"{path}: {bad} vertices are NaN or infinite")
    return parts


def _resolver(path: Path, max_bytes: int, key: str):
    """trimesh's resolver of the files a mesh file names (a glTF's buffers and images), beside
    `path`, each read as `read_regular_file` reads (a FIFO or a device is refused, unread)."""
    from trimesh.resolvers import FilePathResolver

    class _Resolver(FilePathResolver):
        def get(self, name: str) -> bytes:
            for candidate in (name.strip(), name.strip().lstrip("/"), os.path.split(name)[-1]):
                try:
                    found = self.absolute(candidate)
                except ValueError:
                    continue
                if os.path.lexists(found):
                    return read_regular_file(found, max_bytes, key,
                                             f"{path}: the file it names {shorten(name)}")
            self.absolute(name)  # the error trimesh gives for a name outside the folder
            raise FileNotFoundError(name)

        def namespaced(self, namespace: str):
            return _resolver(Path(self.parent) / namespace / path.name, max_bytes, key)

    return _Resolver(str(path))


def _failed_check(exc: BaseException) -> str:
    """What a message-less exception (trimesh's bare `assert`s) was raised by: the failed
    statement and where it is, e.g. "assert 0 <= start (trimesh/exchange/gltf.py:1562)"."""
    import traceback

    frames = traceback.extract_tb(exc.__traceback__)
    if not frames:
        return "no message"
    last = frames[-1]
    where = "/".join(Path(last.filename).parts[-3:])
    return f"{(last.line or '').strip() or 'no message'} ({where}:{last.lineno})"


def _surfaces(path: Path, data: bytes, loaded, key: str) -> dict:
    """geometry name (None: a lone mesh) -> its `Surface`, by the file's format."""
    import trimesh

    suffix = path.suffix.lower()
    geometry = loaded.geometry if isinstance(loaded, trimesh.Scene) else {None: loaded}
    if suffix in (".glb", ".gltf") and isinstance(loaded, trimesh.Scene):
        return gltf_surfaces(path, gltf_document(path, data) or {}, loaded, key,
                             read_regular_file)
    named, ignored = obj_materials(path, data, key, read_regular_file) if suffix == ".obj" \
        else ({}, [])
    out = {}
    for name, mesh in geometry.items():
        if not hasattr(mesh, "faces"):
            continue
        material = getattr(getattr(mesh, "visual", None), "material", None)
        own = named.get(getattr(material, "name", None), Surface())
        uv = trimesh_uv(mesh) if own.texture is not None else None
        if own.texture is not None and uv is None:
            ignored.append("map_Kd on faces without texture coordinates")
            own = own._replace(texture=None)
        out[name] = own._replace(uv=uv, colors=vertex_colours(mesh, linear=False))
    warn_ignored(path, ignored)
    return out


def _part(node: str | None, mesh, matrix: np.ndarray | None,
          surface: Surface | None = None) -> MeshPart:
    """A MeshPart of a trimesh.Trimesh, moved by the (4, 4) node `matrix` (None: as it is),
    with its `surface` (the file's base colour, texture, UVs, vertex colours)."""
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    if matrix is not None:
        vertices = vertices @ matrix[:3, :3].T + matrix[:3, 3]
    factor = getattr(getattr(mesh.visual, "material", None), "baseColorFactor", None)
    diffuse = None
    if factor is not None:
        factor = np.asarray(factor)
        diffuse = factor[:3].astype(np.float64)
        if factor.dtype == np.uint8:  # trimesh keeps glTF's factor as 0..255
            diffuse = diffuse / 255.0
    surface = surface or Surface()
    if surface.diffuse is not None:   # the file's own numbers, not trimesh's 8-bit ones
        diffuse = surface.diffuse
    return MeshPart(node, vertices, np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3),
                    diffuse, surface.texture, surface.uv, surface.colors)


def _scene_parts(loaded, order: list[str], surfaces: dict) -> list[MeshPart]:
    """Every instance of a geometry in a trimesh.Scene's graph (its world transform applied),
    ordered by the node's place in `order` (the file's node names), then depth-first."""
    graph = loaded.graph
    rank = {name: i for i, name in enumerate(order)}
    walk, stack = [], [graph.base_frame]
    while stack:  # depth-first, children in trimesh's order
        node = stack.pop()
        walk.append(node)
        stack.extend(reversed(graph.transforms.children.get(node, [])))
    placed = {node: i for i, node in enumerate(walk)}
    nodes = sorted(graph.nodes_geometry,
                   key=lambda n: (rank.get(n, len(rank)), placed.get(n, len(placed)), n))
    parts = []
    for node in nodes:
        matrix, geometry = graph[node]
        mesh = loaded.geometry.get(geometry)
        if mesh is not None and hasattr(mesh, "faces"):
            parts.append(_part(node, mesh, np.asarray(matrix, dtype=np.float64),
                               surfaces.get(geometry)))
    return parts


def _node_order(path: Path, data: bytes) -> list[str]:
    """The node names of a glTF/GLB file in the file's order ([] for other formats, or when
    the JSON cannot be read: trimesh's own order is used then)."""
    suffix = path.suffix.lower()
    try:
        if suffix == ".glb":
            length = struct.unpack_from("<I", data, 12)[0]
            document = json.loads(data[20:20 + length])
        elif suffix == ".gltf":
            document = json.loads(data)
        else:
            return []
        nodes = document.get("nodes", [])
        return [n["name"] for n in nodes if isinstance(n, dict) and isinstance(n.get("name"), str)]
    except (ValueError, struct.error, AttributeError, RecursionError):
        return []


# A face line of an OBJ file with an index 0 in it (OBJ counts from 1; negative indices count
# back from the last vertex; 0 means nothing, and trimesh would read it as the last vertex).
_OBJ_ZERO_INDEX = re.compile(rb"^[ \t]*f[ \t][^\n]*?(?<=[ \t/])[+-]?0+(?=[/ \t\r\n]|$)", re.M)


def check_mesh_bytes(path: Path, data: bytes, key: str) -> None:
    """SceneError for what the mesh readers would misreport: binary data in a text OBJ, an OBJ
    index 0, an STL that is neither binary nor text, a truncated GLB or glTF."""
    suffix = path.suffix.lower()
    if suffix == ".obj":
        if b"\0" in data:
            raise SceneError(key, f"{path} holds binary data (a NUL byte at {data.index(0)}): "
                                  "an OBJ file is text")
        zero = _OBJ_ZERO_INDEX.search(data)
        if zero:
            line = data.count(b"\n", 0, zero.start()) + 1
            raise SceneError(key, f"{path}: line {line}: face index 0 (OBJ indices start at 1)")
    elif suffix == ".stl":
        n = struct.unpack_from("<I", data, 80)[0] if len(data) >= 84 else None
        binary = n is not None and len(data) == 84 + 50 * n
        text = data.lstrip()[:5].lower() == b"solid" and b"\0" not in data
        if not (binary or text):
            expect = (f"its header says {n} triangles, {84 + 50 * n} bytes"
                      if n is not None else "shorter than the 84-byte header")
            raise SceneError(key, f"{path} is neither a text STL (it does not begin with "
                                  f"'solid' or holds NUL bytes) nor a binary STL ({expect}; "
                                  f"the file has {len(data)})")
    elif suffix == ".glb":
        if len(data) < 12 or data[:4] != b"glTF":
            raise SceneError(key, f"{path} is not a GLB file (no 'glTF' header)")
        length = struct.unpack_from("<I", data, 8)[0]
        if length != len(data):
            raise SceneError(key, f"{path} is truncated or padded: its header says {length} "
                                  f"bytes, the file has {len(data)}")
    elif suffix == ".gltf":
        try:
            json.loads(data)
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise SceneError(key, f"{path} is not valid glTF JSON (truncated?): {exc}") from None
        except RecursionError:
            raise SceneError(key, f"{path}: glTF JSON nested too deeply") from None
    if suffix in (".gltf", ".glb"):
        document = gltf_document(path, data)
        check_node_tree(path, document, key)
        check_layout(path, document, data, key)
