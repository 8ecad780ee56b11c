"""Scene files: TOML (for people) or JSON (for programs), one schema; see scenes/README.md.

Loading never executes code: TOML and JSON are parsed as data, and meshes are read by trimesh's
loaders for a fixed list of data formats.  Every problem raises `SceneError` naming the file, the
key (e.g. `objects[2].material.shininess`) and what is wrong.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np

from . import primitives
from .scene import (AreaLight, Camera, DirectionalLight, Material, PointLight, Scene, SceneError,
                    SpotLight)

MESH_FORMATS = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf")

# Allowed keys per table; anything else is an error (a typo must not be silently ignored).
TOP_KEYS = {"name", "image", "camera", "ambient", "render", "materials", "lights", "objects"}
IMAGE_KEYS = {"width", "height", "background"}
CAMERA_KEYS = {"eye", "target", "up", "fov_y", "near"}
RENDER_KEYS = {"max_depth"}
MATERIAL_KEYS = {"ambient", "diffuse", "specular", "shininess", "reflectivity", "transparency",
                 "ior"}
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


def load_scene(path: str | Path) -> Scene:
    """Read a scene from a `.toml` or `.json` file.  Raises SceneError (a ValueError)."""
    path = Path(path)
    try:
        text = path.read_bytes()
    except OSError as exc:
        raise SceneError("", f"cannot read the scene file: {exc.strerror or exc}",
                         str(path)) from None
    try:
        if path.suffix.lower() == ".json":
            data = json.loads(text)
        elif path.suffix.lower() == ".toml":
            data = tomllib.loads(text.decode("utf-8"))
        else:
            raise SceneError("", "a scene file must end in .toml or .json", str(path))
    except (tomllib.TOMLDecodeError, json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise SceneError("", f"not valid {path.suffix[1:].upper()}: {exc}", str(path)) from None
    try:
        return scene_from_dict(data, base_dir=path.parent, default_name=path.stem)
    except SceneError as exc:
        raise exc.in_file(str(path)) from None


def scene_from_dict(data, base_dir: Path = Path("."), default_name: str = "scene") -> Scene:
    """Build a Scene from parsed TOML/JSON data; mesh paths are relative to `base_dir`."""
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
        raise SceneError("name", f"expected a string, got {name!r}")
    return _build("", Scene,
                  camera=_build("camera", Camera, **camera),
                  objects=[_object(o, f"objects[{i}]", named, base_dir)
                           for i, o in enumerate(objects)],
                  lights=[_light(lt, f"lights[{i}]") for i, lt in enumerate(lights)],
                  name=name, **kwargs)


# ---------------------------------------------------------------------------------------------

def _table(value, key: str, allowed: set[str] | None) -> dict:
    if not isinstance(value, dict):
        raise SceneError(key or "(top level)", f"expected a table, got {type(value).__name__}")
    if allowed is not None:
        unknown = sorted(set(value) - allowed)
        if unknown:
            prefix = f"{key}." if key else ""
            raise SceneError(f"{prefix}{unknown[0]}",
                             f"unknown key (allowed here: {', '.join(sorted(allowed))})")
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
        raise SceneError(f"{key}.type", f"unknown {what} type {kind!r} "
                                        f"(one of: {', '.join(allowed_by_type)})")
    return _table(table, key, allowed_by_type[kind]), kind


def _light(value, key: str):
    table, kind = _typed(value, key, LIGHT_KEYS, "light")
    args = {k: v for k, v in table.items() if k != "type"}
    if kind in ("rect", "disk", "sphere"):
        _required(table, "center", key)
        return _build(key, AreaLight, shape=kind, **args)
    cls = {"point": PointLight, "directional": DirectionalLight, "spot": SpotLight}[kind]
    return _build(key, cls, **args)


def _object(value, key: str, named: dict[str, Material], base_dir: Path):
    table, kind = _typed(value, key, OBJECT_KEYS, "object")
    name = table.get("name", f"{kind}{key[len('objects'):]}")
    if not isinstance(name, str):
        raise SceneError(f"{key}.name", f"expected a string, got {name!r}")

    material = table.get("material")
    if material is None:
        material = Material()
    elif isinstance(material, str):
        if material not in named:
            raise SceneError(f"{key}.material", f"no material named {material!r} in [materials]")
        material = named[material]
    else:
        material = _material(material, f"{key}.material")

    transform = _build(f"{key}.transform", primitives.Transform,
                       **_table(table.get("transform", {}), f"{key}.transform", TRANSFORM_KEYS))
    args = {k: v for k, v in table.items() if k not in COMMON_OBJECT_KEYS}
    if kind == "mesh":
        if ("path" in table) == ("vertices" in table or "faces" in table):
            raise SceneError(key, "a mesh needs either `path` or inline `vertices` and `faces`")
        if "path" in table:
            vertices, faces = _read_mesh(table["path"], f"{key}.path", base_dir)
        else:
            vertices, faces = _inline_mesh(table, key)
        return _build(key, primitives.mesh, name=name, vertices=vertices, faces=faces,
                      material=material, transform=transform)
    builder = {"sphere": primitives.sphere, "plane": primitives.plane, "box": primitives.box}[kind]
    if kind == "sphere":
        for required in ("center", "radius"):
            _required(table, required, key)
    return _build(key, builder, name=name, material=material, transform=transform, **args)


def _inline_mesh(table: dict, key: str) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and faces written in the scene file itself (as `save_scene` writes them)."""
    vertices, faces = _required(table, "vertices", key), _required(table, "faces", key)
    try:
        v = np.array(vertices, dtype=np.float64)
    except (TypeError, ValueError):
        raise SceneError(f"{key}.vertices", "expected a list of [x, y, z] numbers") from None
    if v.ndim != 2 or v.shape[1:] != (3,):
        raise SceneError(f"{key}.vertices", f"expected a list of [x, y, z], got shape {v.shape}")
    f = np.array(faces)
    if f.size and (f.ndim != 2 or f.shape[1:] != (3,) or
                   not np.issubdtype(f.dtype, np.integer)):
        raise SceneError(f"{key}.faces", "expected a list of [i, j, k] whole numbers")
    return v, f


def _read_mesh(rel, key: str, base_dir: Path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and faces of a mesh file, as stored (seam duplicates kept), with glTF node
    transforms applied."""
    import trimesh  # deferred: trimesh's import is slow and only meshes need it here

    if not isinstance(rel, str) or not rel:
        raise SceneError(key, f"expected a file path, got {rel!r}")
    path = base_dir / rel
    if path.suffix.lower() not in MESH_FORMATS:
        raise SceneError(key, f"{rel!r}: unsupported mesh format (use one of "
                              f"{', '.join(MESH_FORMATS)})")
    if not path.is_file():
        raise SceneError(key, f"mesh file not found: {path}")
    try:
        loaded = trimesh.load(str(path), process=False)
    except Exception as exc:  # trimesh raises many types for malformed files
        raise SceneError(key, f"cannot parse mesh {path}: {type(exc).__name__}: {exc}") from None
    if isinstance(loaded, trimesh.Scene):
        if not loaded.geometry:
            raise SceneError(key, f"{path} holds no geometry")
        loaded = loaded.to_mesh()  # applies each node's transform; vertices are not merged
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise SceneError(key, f"{path} holds no triangles")
    vertices = np.asarray(loaded.vertices, dtype=np.float64)
    if not np.isfinite(vertices).all():
        bad = int((~np.isfinite(vertices).all(axis=1)).sum())
        raise SceneError(key, f"{path}: {bad} vertices are NaN or infinite")
    return vertices, np.asarray(loaded.faces, dtype=np.int64)



def scene_to_dict(scene: Scene) -> dict:
    """The scene as plain data in the file schema: every object as an inline mesh of its
    world-space triangles (analytic spheres and planes become their tessellations), every
    material inline.  `scene_from_dict(scene_to_dict(s))` gives the same triangles, camera and
    lights, so a saved scene reproduces any mask exactly."""

    def material(m: Material) -> dict:
        return {"ambient": m.ambient.tolist(), "diffuse": m.diffuse.tolist(),
                "specular": m.specular.tolist(), "shininess": m.shininess,
                "reflectivity": m.reflectivity, "transparency": m.transparency, "ior": m.ior}

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
    """Write `scene` as a self-contained JSON scene file (atomically)."""
    from .files import atomic_write

    data = json.dumps(scene_to_dict(scene), indent=1).encode()
    with atomic_write(path) as f:
        f.write(data)
