"""Scene files: TOML (for people) or JSON (for programs), one schema; see scenes/README.md.

Loading never executes code: TOML and JSON are parsed as data, and meshes are read by trimesh's
loaders for a fixed list of data formats.  Every problem raises `SceneError` naming the file, the
key (e.g. `objects[2].material.shininess`) and what is wrong.
"""

from __future__ import annotations

import json
import os
import re
import stat
import struct
import tomllib
from pathlib import Path
from typing import NamedTuple

import numpy as np

from shadowvol import primitives
from shadowvol.errors import out_of_memory_while
from shadowvol.io import atomic_write
from shadowvol.scene import (
    AreaLight,
    Camera,
    DirectionalLight,
    Material,
    Object,
    PointLight,
    Scene,
    SceneError,
    SpotLight,
    reject_unknown_keys,
    shorten,
)

MESH_FORMATS = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf")

# Limits on what a scene file may make us read and build (all checked before the work):
# the sizes of the scene file and of each mesh file (bytes; `load_scene` takes others), how
# deeply its tables and lists may nest (the schema needs 4: objects[i].vertices[j][k]) and
# how long any one list may be (16.7M: an inline mesh of 5.6M unwelded triangles).
MAX_SCENE_FILE_BYTES = 256 << 20
MAX_MESH_FILE_BYTES = 1 << 30
MAX_NESTING = 16
MAX_LIST_LENGTH = 1 << 24

# Allowed keys per table; anything else is an error (a typo must not be silently ignored).
TOP_KEYS = {"name", "image", "camera", "ambient", "render", "materials", "lights", "objects"}
IMAGE_KEYS = {"width", "height", "background"}
CAMERA_KEYS = {"eye", "target", "up", "fov_y", "near"}
RENDER_KEYS = {"max_depth"}
MATERIAL_KEYS = {"ambient", "diffuse", "specular", "shininess", "reflectivity", "transparency",
                 "ior", "emission"}
LIGHT_KEYS = {
    "point": {"type", "position", "color", "intensity"},
    "directional": {"type", "direction", "color", "intensity"},
    "spot": {"type", "position", "direction", "cone_angle", "color", "intensity"},
}
AREA_KEYS = {"type", "center", "color", "intensity", "samples", "pattern", "seed"}
LIGHT_KEYS.update({"rect": AREA_KEYS | {"normal", "size"}, "disk": AREA_KEYS | {"normal", "radius"},
                   "sphere": AREA_KEYS | {"radius"}})
TRANSFORM_KEYS = {"scale", "rotation", "translation"}
COMMON_OBJECT_KEYS = {"type", "name", "material", "transform"}
OBJECT_KEYS = {
    "mesh": COMMON_OBJECT_KEYS | {"path", "vertices", "faces"},
    "sphere": COMMON_OBJECT_KEYS | {"center", "radius", "subdivisions"},
    "plane": COMMON_OBJECT_KEYS | {"point", "normal", "size"},
    "box": COMMON_OBJECT_KEYS | {"center", "size"},
}


def load_scene(path: str | Path, *, max_bytes: int = MAX_SCENE_FILE_BYTES,
               max_mesh_bytes: int = MAX_MESH_FILE_BYTES) -> Scene:
    """Read a scene from a `.toml` or `.json` file, which must be a regular file of at most
    `max_bytes` (its meshes: `max_mesh_bytes` each).  Raises SceneError (a ValueError)."""
    path = Path(path)
    with out_of_memory_while(f"reading {path}"):
        return _load_scene(path, max_bytes, max_mesh_bytes)


def _load_scene(path: Path, max_bytes: int, max_mesh_bytes: int) -> Scene:
    if path.suffix.lower() not in (".json", ".toml"):
        raise SceneError("", "a scene file must end in .toml or .json", str(path))
    try:
        text = read_regular_file(path, max_bytes, what="the scene file")
    except SceneError as exc:
        raise exc.in_file(str(path)) from None
    try:
        if path.suffix.lower() == ".json":
            data = json.loads(text, object_pairs_hook=_JsonObject.of)
        else:
            data = tomllib.loads(text.decode("utf-8"))
    except (tomllib.TOMLDecodeError, json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise SceneError("", f"not valid {path.suffix[1:].upper()}: {exc}", str(path)) from None
    except RecursionError:
        raise SceneError("", f"nested more than {MAX_NESTING} levels deep", str(path)) from None
    try:
        return scene_from_dict(data, base_dir=path.parent, default_name=path.stem,
                               max_mesh_bytes=max_mesh_bytes)
    except SceneError as exc:
        raise exc.in_file(str(path)) from None


def read_regular_file(path: Path, max_bytes: int, key: str = "", what: str | None = None
                      ) -> bytes:
    """The bytes of `path` if it is a regular file of at most `max_bytes`, else a SceneError
    under `key` saying what it is (naming it as `what`, default the path).  Opened without blocking (a FIFO would wait for a writer),
    checked with fstat on the open file, then read to at most max_bytes + 1 (a file that grows
    meanwhile is still caught)."""
    what = what or str(path)
    fd = _open_regular(path, max_bytes, key, what)
    with os.fdopen(fd, "rb") as f:
        data = f.read(max_bytes + 1)
    if len(data) > max_bytes:
        raise SceneError(key, f"{what} grew past {max_bytes} bytes while being read")
    return data


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


class _JsonObject(dict):
    """A JSON object that remembers the keys it was given more than once (JSON allows them,
    with the last winning; a scene refuses them, as TOML does): `duplicates`."""

    duplicates: tuple = ()

    @classmethod
    def of(cls, pairs: list) -> "_JsonObject":
        obj = cls(pairs)
        if len(obj) != len(pairs):
            seen: set = set()
            obj.duplicates = tuple(k for k, _ in pairs if k in seen or seen.add(k))
        return obj


_CONTAINERS = frozenset({list, dict, _JsonObject})


def check_shape(data) -> None:
    """SceneError unless `data` (parsed TOML/JSON) nests at most MAX_NESTING levels, every list
    holds at most MAX_LIST_LENGTH items and no JSON object repeats a key.  Iterative: the depth
    of the data never becomes the depth of the Python stack."""
    stack = [(data, 0, "")]
    while stack:
        node, depth, key = stack.pop()
        if depth > MAX_NESTING:
            raise SceneError(key, f"nested more than {MAX_NESTING} levels deep")
        if isinstance(node, dict):
            if getattr(node, "duplicates", ()):
                dup = node.duplicates[0]
                raise SceneError(f"{key}.{dup}" if key else str(dup),
                                 "duplicate key (given more than once in this object)")
            stack.extend((v, depth + 1, f"{key}.{k}" if key else str(k)) for k, v in node.items())
        elif isinstance(node, list):
            if len(node) > MAX_LIST_LENGTH:
                raise SceneError(key, f"a list of {len(node)} items, more than the limit of "
                                      f"{MAX_LIST_LENGTH}")
            for i, item in enumerate(node):
                kind = type(item)
                if kind is list and _CONTAINERS.isdisjoint(map(type, item)):
                    # a list of plain values (a vertex): its own depth and length only
                    if depth + 1 > MAX_NESTING or len(item) > MAX_LIST_LENGTH:
                        stack.append((item, depth + 1, f"{key}[{i}]"))
                elif kind in _CONTAINERS:
                    stack.append((item, depth + 1, f"{key}[{i}]"))


def scene_from_dict(data, base_dir: Path = Path("."), default_name: str = "scene",
                    max_mesh_bytes: int = MAX_MESH_FILE_BYTES) -> Scene:
    """Build a Scene from parsed TOML/JSON data; mesh paths are relative to `base_dir`, and
    each mesh file may be at most `max_mesh_bytes`."""
    check_shape(data)
    _table(data, "", TOP_KEYS)
    image = _table(data.get("image", {}), "image", IMAGE_KEYS)
    camera = _table(_required(data, "camera", ""), "camera", CAMERA_KEYS)
    render = _table(data.get("render", {}), "render", RENDER_KEYS)

    materials = _table(data.get("materials", {}), "materials", None)
    named = {name: _material(m, f"materials.{name}") for name, m in materials.items()}

    lights = _list(data.get("lights", []), "lights")
    objects = _list(_required(data, "objects", ""), "objects")

    kwargs = {}
    for key in ("width", "height"):
        if key in image:
            kwargs[key] = image[key]
    if "background" in image:
        kwargs["background"] = image["background"]
    if "ambient" in data:
        kwargs["ambient"] = data["ambient"]
    if "max_depth" in render:
        kwargs["max_depth"] = render["max_depth"]
    name = data.get("name", default_name)
    if not isinstance(name, str):
        raise SceneError("name", f"expected a string, got {shorten(name)}")
    return _build("", Scene,
                  camera=_build("camera", Camera, **camera),
                  objects=[part for i, o in enumerate(objects)
                           for part in _object(o, f"objects[{i}]", named, base_dir,
                                               max_mesh_bytes)],
                  lights=[_light(lt, f"lights[{i}]") for i, lt in enumerate(lights)],
                  name=name, **kwargs)


# ---------------------------------------------------------------------------------------------

def _table(value, key: str, allowed: set[str] | None) -> dict:
    if not isinstance(value, dict):
        raise SceneError(key or "(top level)", f"expected a table, got {type(value).__name__}")
    if allowed is not None:
        reject_unknown_keys(value, allowed, key)
    return value


def _list(value, key: str) -> list:
    if not isinstance(value, list):
        raise SceneError(key, f"expected a list, got {type(value).__name__}")
    return value


def _required(table: dict, key: str, prefix: str):
    if key not in table:
        raise SceneError(f"{prefix}.{key}" if prefix else key, "missing")
    return table[key]


def _build(key: str, cls, **kwargs):
    """Call a scene-model constructor, prefixing any SceneError with `key`."""
    try:
        return cls(**kwargs)
    except SceneError as exc:
        raise (exc.under(key) if key else exc) from None


def _material(value, key: str) -> Material:
    return _build(key, Material, **_table(value, key, MATERIAL_KEYS))


def _typed(value, key: str, allowed_by_type: dict[str, set[str]], what: str) -> tuple[dict, str]:
    """A table with a `type` key naming one of `allowed_by_type`, checked against that type's
    allowed keys.  Returns (table, type)."""
    table = _table(value, key, None)
    kind = _required(table, "type", key)
    if kind not in allowed_by_type:
        raise SceneError(f"{key}.type", f"unknown {what} type {shorten(kind)} "
                                        f"(one of: {', '.join(allowed_by_type)})")
    return _table(table, key, allowed_by_type[kind]), kind


REQUIRED_LIGHT_KEYS = {"point": ("position",), "directional": ("direction",),
                       "spot": ("position", "direction")}


def _light(value, key: str):
    table, kind = _typed(value, key, LIGHT_KEYS, "light")
    args = {k: v for k, v in table.items() if k != "type"}
    if kind in ("rect", "disk", "sphere"):
        _required(table, "center", key)
        return _build(key, AreaLight, shape=kind, **args)
    cls = {"point": PointLight, "directional": DirectionalLight, "spot": SpotLight}[kind]
    for name in REQUIRED_LIGHT_KEYS[kind]:
        _required(table, name, key)
    return _build(key, cls, **args)


def light_from_dict(value, key: str = "light"):
    """One light from a table of the scene-file schema (`[[lights]]`), e.g. a batch job's light
    override; SceneError naming `key` when it is wrong."""
    try:
        return _light(value, key)
    except TypeError as exc:  # a required field left out: "missing 1 required ... 'position'"
        missing = str(exc).rsplit(":", 1)[-1].strip() or str(exc)
        raise SceneError(key, f"missing {missing}") from None


def _object(value, key: str, named: dict[str, Material], base_dir: Path,
            max_mesh_bytes: int = MAX_MESH_FILE_BYTES) -> list[Object]:
    """The objects of one `[[objects]]` entry: one, or for a mesh file of several parts (glTF
    nodes, the meshes of a multi-mesh file) one per part (`mesh_parts`)."""
    table, kind = _typed(value, key, OBJECT_KEYS, "object")
    name = table.get("name", f"{kind}{key[len('objects'):]}")
    if not isinstance(name, str):
        raise SceneError(f"{key}.name", f"expected a string, got {shorten(name)}")

    material = table.get("material")
    if material is None:
        material = Material()
    elif isinstance(material, str):
        if material not in named:
            raise SceneError(f"{key}.material",
                             f"no material named {shorten(material)} in [materials]")
        material = named[material]
    else:
        material = _material(material, f"{key}.material")

    transform = _build(f"{key}.transform", primitives.Transform,
                       **_table(table.get("transform", {}), f"{key}.transform", TRANSFORM_KEYS))
    args = {k: v for k, v in table.items() if k not in COMMON_OBJECT_KEYS}
    if kind == "mesh":
        if ("path" in table) == ("vertices" in table or "faces" in table):
            raise SceneError(key, "a mesh needs either `path` or inline `vertices` and `faces`")
        if "vertices" in table:
            vertices, faces = _inline_mesh(table, key)
            return [_build(key, primitives.mesh, name=name, vertices=vertices, faces=faces,
                           material=material, transform=transform)]
        parts = _read_mesh(table["path"], f"{key}.path", base_dir, max_mesh_bytes)
        return [_build(key, primitives.mesh, name=part_name(name, part, len(parts)),
                       vertices=part.vertices, faces=part.faces,
                       material=part_material(material, part, "material" in table),
                       transform=transform) for part in parts]
    builder = {"sphere": primitives.sphere, "plane": primitives.plane, "box": primitives.box}[kind]
    if kind == "sphere":
        for required in ("center", "radius"):
            _required(table, required, key)
    return [_build(key, builder, name=name, material=material, transform=transform, **args)]


def _inline_mesh(table: dict, key: str) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and faces written in the scene file itself (as `save_scene` writes them)."""
    vertices, faces = _required(table, "vertices", key), _required(table, "faces", key)
    bad = _first_not_triple(vertices, _REALS, "iuf")
    if bad is not None:
        raise SceneError(f"{key}.vertices{bad[0]}", f"expected [x, y, z] numbers, got {bad[1]}")
    v = np.array(vertices, dtype=np.float64).reshape(-1, 3)
    bad = _first_not_triple(faces, _WHOLES, "iu")
    if bad is not None:
        raise SceneError(f"{key}.faces{bad[0]}", f"expected [i, j, k] whole numbers, got {bad[1]}")
    f = np.array(faces, dtype=np.int64).reshape(-1, 3)
    return v, f


# The exact types a number may have in parsed data (JSON and TOML give int and float; code
# calling `scene_from_dict` may give numpy's).  Exact: a bool is no int here.
_WHOLES = (int, np.int64, np.int32)
_REALS = (float, np.float64, np.float32) + _WHOLES


def _first_not_triple(rows, types: tuple, kinds: str) -> tuple[str, str] | None:
    """Where `rows` is not a list of 3-lists of values whose type is exactly one of `types`
    (or an (n, 3) array of dtype kind in `kinds`), as ("[i]", the value cut short), or
    ("", ...) when `rows` is neither; None when it is."""
    if isinstance(rows, np.ndarray) and rows.dtype.kind in kinds and rows.ndim == 2 \
            and rows.shape[1] == 3:
        return None
    if type(rows) is not list:
        return "", shorten(rows)
    for i, row in enumerate(rows):
        if not (type(row) is list and len(row) == 3 and type(row[0]) in types
                and type(row[1]) in types and type(row[2]) in types):
            return f"[{i}]", shorten(row)
    return None


class MeshPart(NamedTuple):
    """One mesh of a mesh file, in the file's own space with its node transform applied.

    node     : the node's (or geometry's) name in the file, None for a single-mesh file
    vertices : (n, 3) float64;  faces : (m, 3) int64, as stored (seam duplicates kept)
    diffuse  : (3,) float64, the part's glTF baseColorFactor (linear RGB), or None
    """

    node: str | None
    vertices: np.ndarray
    faces: np.ndarray
    diffuse: np.ndarray | None


def part_name(name: str, part: MeshPart, parts: int) -> str:
    """The object name of a part: the entry's name, then `/node` when the file has several."""
    return name if parts == 1 or part.node is None else f"{name}/{part.node}"


def part_material(material: Material, part: MeshPart, given: bool) -> Material:
    """The material of a part: the entry's when it names one (`given`), else the part's own
    base colour as its diffuse colour, else the default."""
    if given or part.diffuse is None:
        return material
    return Material(diffuse=part.diffuse)


def _read_mesh(rel, key: str, base_dir: Path, max_bytes: int = MAX_MESH_FILE_BYTES
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
        loaded = trimesh.load(str(path), process=False)
    except ImportError as exc:  # an optional package of trimesh's, for this format
        raise SceneError(key, f"reading {path} needs the Python package {exc.name!r}, which is "
                              f"not installed (pip install {exc.name})") from None
    except Exception as exc:  # trimesh raises many types for malformed files
        raise SceneError(key, f"cannot parse mesh {path}: {type(exc).__name__}: {exc}") from None
    if isinstance(loaded, trimesh.Scene):
        if not loaded.geometry:
            raise SceneError(key, f"{path} holds no geometry")
        parts = _scene_parts(loaded, _node_order(path, data))
    elif isinstance(loaded, trimesh.Trimesh):
        parts = [_part(None, loaded, None)]
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


def _part(node: str | None, mesh, matrix: np.ndarray | None) -> MeshPart:
    """A MeshPart of a trimesh.Trimesh, moved by the (4, 4) node `matrix` (None: as it is)."""
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
    return MeshPart(node, vertices, np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3),
                    diffuse)


def _scene_parts(loaded, order: list[str]) -> list[MeshPart]:
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
            parts.append(_part(node, mesh, np.asarray(matrix, dtype=np.float64)))
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



def scene_to_dict(scene: Scene) -> dict:
    """The scene as plain data in the file schema: every object as an inline mesh of its
    world-space triangles (analytic spheres and planes become their tessellations), every
    material inline.  `scene_from_dict(scene_to_dict(s))` gives the same triangles, camera and
    lights, so a saved scene reproduces any mask exactly."""

    def material(m: Material) -> dict:
        return {"ambient": m.ambient.tolist(), "diffuse": m.diffuse.tolist(),
                "specular": m.specular.tolist(), "shininess": m.shininess,
                "reflectivity": m.reflectivity, "transparency": m.transparency, "ior": m.ior,
                "emission": m.emission.tolist()}

    def light(lt) -> dict:
        out = {"color": lt.color.tolist(), "intensity": lt.intensity}
        if isinstance(lt, PointLight):
            return {"type": "point", "position": lt.position.tolist(), **out}
        if isinstance(lt, DirectionalLight):
            return {"type": "directional", "direction": lt.direction.tolist(), **out}
        if isinstance(lt, AreaLight):
            shape = {"normal": lt.normal, "size": lt.size, "radius": lt.radius}
            return {"type": lt.shape, "center": lt.center.tolist(), "samples": lt.samples,
                    "pattern": lt.pattern, "seed": lt.seed, **out,
                    **{k: (v.tolist() if isinstance(v, np.ndarray) else v)
                       for k, v in shape.items() if v is not None}}
        return {"type": "spot", "position": lt.position.tolist(),
                "direction": lt.direction.tolist(), "cone_angle": lt.cone_angle, **out}

    cam = scene.camera
    return {
        "name": scene.name,
        "ambient": scene.ambient.tolist(),
        "image": {"width": int(scene.width), "height": int(scene.height),
                  "background": scene.background.tolist()},
        "camera": {"eye": cam.eye.tolist(), "target": cam.target.tolist(), "up": cam.up.tolist(),
                   "fov_y": cam.fov_y, "near": cam.near},
        "render": {"max_depth": int(scene.max_depth)},
        "lights": [light(lt) for lt in scene.lights],
        "objects": [{"type": "mesh", "name": o.name, "vertices": o.vertices.tolist(),
                     "faces": o.faces.tolist(), "material": material(o.material)}
                    for o in scene.objects],
    }


def save_scene(scene: Scene, path: str | Path) -> None:
    """Write `scene` as a self-contained scene file (atomically): TOML for a `.toml` path,
    JSON for a `.json` path; any other suffix is a SceneError, since `load_scene` would refuse
    the file."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".toml", ".json"):
        raise SceneError("path", f"a scene file must end in .toml or .json, got {str(path)!r}",
                         str(path))
    data = scene_to_dict(scene)
    text = to_toml(data) if suffix == ".toml" else json.dumps(data, indent=1)
    with atomic_write(path) as f:
        f.write(text.encode("utf-8"))


def to_toml(data: dict) -> str:
    """A scene dict (numbers, strings, booleans, lists, dicts; no None) as TOML: plain keys and
    inline tables at the top, each list of tables as [[key]] sections.  Floats are written with
    repr, so they read back bit for bit."""
    lines, sections = [], []
    for key, value in data.items():
        if isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            sections.append((key, value))
        else:
            lines.append(f"{_toml_key(key)} = {_toml_value(value)}")
    for key, tables in sections:
        for table in tables:
            lines += ["", f"[[{_toml_key(key)}]]"]
            lines += [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"


def _toml_key(key: str) -> str:
    return key if key.replace("_", "").replace("-", "").isalnum() and key.isascii() \
        else json.dumps(key)


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return "nan" if v != v else ("inf" if v > 0 else "-inf") if v in (np.inf, -np.inf) \
            else repr(v)
    if isinstance(value, str):
        return json.dumps(value)  # JSON's string escapes are TOML basic-string escapes
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_toml_key(k)} = {_toml_value(v)}"
                               for k, v in value.items()) + "}"
    raise TypeError(f"cannot write {type(value).__name__} to TOML")
