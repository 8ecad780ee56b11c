"""Scene files: TOML (for people) or JSON (for programs), one schema; see scenes/README.md.

Loading never executes code: TOML and JSON are parsed as data, and meshes are read by trimesh's
loaders for a fixed list of data formats.  Every problem raises `SceneError` naming the file, the
key (e.g. `objects[2].material.shininess`) and what is wrong.  Reading is here; the mesh files
and the bounded file reads are `shadowvol.scenefile_mesh`, writing (`save_scene`, also named
here) `shadowvol.scenefile_write`.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import tomllib
from pathlib import Path

import numpy as np

from shadowvol import primitives
from shadowvol.errors import out_of_memory_while
from shadowvol.scene import (
    BACKGROUND,
    LOOK_AT_CAMERA_KEYS,
    MATRIX_CAMERA_KEYS,
    MIXED_FORMS,
    AreaLight,
    Camera,
    DirectionalLight,
    Material,
    Object,
    PointLight,
    Scene,
    SceneError,
    SpotLight,
    is_number,
    reject_unknown_keys,
    shorten,
)
from shadowvol.scenefile_mesh import (
    MAX_MESH_FILE_BYTES,
    part_material,
    part_name,
    read_mesh,
    read_regular_file,
)
from shadowvol.scenefile_texture import texture_from_dict
from shadowvol.scenefile_write import save_scene  # noqa: F401 (shadowvol.scenefile.save_scene)

# Limits on what a scene file may make us read and build (all checked before the work):
# the size of the scene file (bytes; `load_scene` takes another, and one for each mesh file,
# `scenefile_mesh.MAX_MESH_FILE_BYTES`), how deeply its tables and lists may nest (the schema
# needs 4: objects[i].vertices[j][k]) and how long any one list may be (16.7M: an inline mesh
# of 5.6M unwelded triangles).
MAX_SCENE_FILE_BYTES = 256 << 20
MAX_NESTING = 16
MAX_LIST_LENGTH = 1 << 24

# Allowed keys per table; anything else is an error (a typo must not be silently ignored).
TOP_KEYS = {"name", "image", "camera", "ambient", "render", "materials", "lights", "objects"}
IMAGE_KEYS = {"width", "height", "background"}
CAMERA_KEYS = {"eye", "target", "up", "fov_y", "near", "aperture", "focus_distance",
               "fx", "fy", "cx", "cy", "camera_to_world"}
RENDER_KEYS = {"max_depth"}
MATERIAL_KEYS = {"ambient", "diffuse", "specular", "shininess", "reflectivity", "transparency",
                 "ior", "emission", "roughness", "texture"}
LIGHT_KEYS = {
    "point": {"type", "position", "color", "intensity", "shadows"},
    "directional": {"type", "direction", "color", "intensity", "shadows"},
    "spot": {"type", "position", "direction", "cone_angle", "color", "intensity", "shadows"},
}
AREA_KEYS = {"type", "center", "color", "intensity", "samples", "pattern", "seed", "shadows"}
LIGHT_KEYS.update({"rect": AREA_KEYS | {"normal", "size"}, "disk": AREA_KEYS | {"normal", "radius"},
                   "sphere": AREA_KEYS | {"radius"}})
TRANSFORM_KEYS = {"scale", "rotation", "translation", "matrix"}
# the shadow switches (docs/CONVENTIONS.md, "Shadow switches"); an object's default: true
SWITCH_KEYS = ("cast_shadows", "receive_shadows")
COMMON_OBJECT_KEYS = {"type", "name", "material", "transform", "category", *SWITCH_KEYS}
OBJECT_KEYS = {
    "mesh": COMMON_OBJECT_KEYS | {"path", "vertices", "faces", "uv", "colors"},
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
    named = {name: _material(m, f"materials.{name}", base_dir)
             for name, m in materials.items()}

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
                  camera=camera_from_dict(camera, "camera"),
                  objects=[part for i, o in enumerate(objects)
                           for part in _object(o, f"objects[{i}]", named, base_dir,
                                               max_mesh_bytes)],
                  lights=[_light(lt, f"lights[{i}]") for i, lt in enumerate(lights)],
                  name=name, **kwargs)


# ---------------------------------------------------------------------------------------------

def given(value) -> str:
    """What a scene file gave, in the file's own terms (a table, a list, the string 'x', ...),
    never a Python class name."""
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, str):
        return f"the string {shorten(value)}"
    if is_number(value):
        return f"the number {shorten(value)}"
    return shorten(value)


def _table(value, key: str, allowed: set[str] | None) -> dict:
    if not isinstance(value, dict):
        raise SceneError(key or "(top level)", f"expected a table, got {given(value)}")
    if allowed is not None:
        reject_unknown_keys(value, allowed, key)
    return value


def _list(value, key: str) -> list:
    if not isinstance(value, list):
        raise SceneError(key, f"expected a list, got {given(value)}")
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


def camera_from_dict(table: dict, key: str = "camera") -> Camera:
    """The camera of a `[camera]` table: look-at keys (eye, target, up, fov_y) or matrix keys
    (fx, fy, cx, cy, camera_to_world), never some of both (`Camera`); SceneError naming
    `key.<the key>` when it is wrong."""
    table = _table(table, key, CAMERA_KEYS)
    look_at = [k for k in LOOK_AT_CAMERA_KEYS if k in table]
    matrices = [k for k in MATRIX_CAMERA_KEYS if k in table]
    if look_at and matrices:
        raise SceneError(f"{key}.{matrices[0]}", f"given with {look_at[0]}: {MIXED_FORMS}")
    return _build(key, Camera, **table)


def _material(value, key: str, base_dir: Path = Path(".")) -> Material:
    table = dict(_table(value, key, MATERIAL_KEYS))
    if "texture" in table:   # as `save_scene` writes a texture: its file (and image)
        table["texture"] = texture_from_dict(table["texture"], f"{key}.texture", base_dir,
                                             read_regular_file)
    return _build(key, Material, **table)


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
    nodes, the meshes of a multi-mesh file) one per part (`scenefile_mesh.read_mesh`), each
    with the entry's shadow switches."""
    parts = _object_parts(value, key, named, base_dir, max_mesh_bytes)
    switches = {k: value[k] for k in SWITCH_KEYS if k in value}
    if "category" in value:
        category = value["category"]
        if not isinstance(category, str) or not category:
            raise SceneError(f"{key}.category", f"expected a class name (a non-empty "
                                                f"string), got {given(category)}")
        switches["category"] = category
    elif value.get("type") == "plane":
        switches["category"] = BACKGROUND   # a plane is the stage: a floor, a wall
    if not switches:
        return parts
    return [_build(key, functools.partial(dataclasses.replace, part), **switches)
            for part in parts]


def _object_parts(value, key: str, named: dict[str, Material], base_dir: Path,
                  max_mesh_bytes: int = MAX_MESH_FILE_BYTES) -> list[Object]:
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
        material = _material(material, f"{key}.material", base_dir)

    transform = _transform(table.get("transform", {}), f"{key}.transform")
    args = {k: v for k, v in table.items() if k not in COMMON_OBJECT_KEYS}
    if kind == "mesh":
        if ("path" in table) == ("vertices" in table or "faces" in table):
            raise SceneError(key, "a mesh needs either `path` or inline `vertices` and `faces`")
        if "vertices" in table:
            vertices, faces = _inline_mesh(table, key)
            return [_build(key, primitives.mesh, name=name, vertices=vertices, faces=faces,
                           material=material, transform=transform, uv=table.get("uv"),
                           colors=table.get("colors"))]
        parts = read_mesh(table["path"], f"{key}.path", base_dir, max_mesh_bytes)
        model = _model_key(base_dir / table["path"], transform)
        return [dataclasses.replace(
                    _build(key, primitives.mesh, name=part_name(name, part, len(parts)),
                           vertices=part.vertices, faces=part.faces,
                           material=part_material(material, part, "material" in table),
                           transform=transform, uv=part.uv, colors=part.colors),
                    category=Path(table["path"]).stem,
                    model=model if part.node is None else f"{model}#{part.node}")
                for part in parts]
    builder = {"sphere": primitives.sphere, "plane": primitives.plane, "box": primitives.box}[kind]
    if kind == "sphere":
        for required in ("center", "radius"):
            _required(table, required, key)
    return [_build(key, builder, name=name, material=material, transform=transform, **args)]


def _transform(value, key: str) -> primitives.Transform:
    """`{ scale, rotation, translation }` or `{ matrix = [[4x4]] }` (a similarity: rotation,
    one scale, translation), never both."""
    table = _table(value, key, TRANSFORM_KEYS)
    if "matrix" in table and len(table) > 1:
        other = sorted(set(table) - {"matrix"})[0]
        raise SceneError(f"{key}.{other}", "given with matrix: give the matrix alone, or "
                                           "scale, rotation and translation")
    return _build(key, primitives.Transform, **table)


def _model_key(path: Path, transform: primitives.Transform) -> str:
    """The model a mesh file's object is an instance of: the file (resolved) at its scale
    (the scale is the model's; the pose is the rest of the transform)."""
    scale = ",".join(repr(float(x)) for x in transform.scale)
    return f"{path.resolve()}@{scale}"


def _inline_mesh(table: dict, key: str) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and faces written in the scene file itself (as `save_scene` writes them)."""
    vertices, faces = _required(table, "vertices", key), _required(table, "faces", key)
    bad = _first_not_triple(vertices, _REALS, "iuf")
    if bad is not None:
        raise SceneError(f"{key}.vertices{bad[0]}", f"expected [x, y, z] numbers, got {bad[1]}")
    v = _array(vertices, np.float64, f"{key}.vertices", "a coordinate of at most 1.8e308")
    bad = _first_not_triple(faces, _WHOLES, "iu")
    if bad is not None:
        raise SceneError(f"{key}.faces{bad[0]}", f"expected [i, j, k] whole numbers, got {bad[1]}")
    f = _array(faces, np.int64, f"{key}.faces", f"an index in 0..{len(v) - 1}")
    return v, f


def _array(rows, dtype, key: str, wanted: str) -> np.ndarray:
    """(n, 3) array of checked triples; a number past `dtype` (an index of 2**63, a coordinate
    of 1e400) is a SceneError naming it instead of numpy's OverflowError."""
    try:
        return np.array(rows, dtype=dtype).reshape(-1, 3)
    except OverflowError:
        i, j = next((i, j) for i, row in enumerate(rows) for j, x in enumerate(row)
                    if not _fits(x, dtype))
        raise SceneError(f"{key}[{i}][{j}]", f"expected {wanted}, got "
                                             f"{shorten(rows[i][j])}") from None


def _fits(x, dtype) -> bool:
    try:
        np.array([x], dtype=dtype)
        return True
    except OverflowError:
        return False


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


