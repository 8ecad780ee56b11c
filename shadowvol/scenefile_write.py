"""Writing scenes: `save_scene` (TOML or JSON) of `scene_to_dict`, the file schema with every
object an inline mesh of its world-space triangles, so a saved scene reproduces its masks."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from shadowvol.io import atomic_write
from shadowvol.scene import (
    AreaLight,
    DirectionalLight,
    Material,
    PointLight,
    Scene,
    SceneError,
)


def scene_to_dict(scene: Scene) -> dict:
    """The scene as plain data in the file schema: every object as an inline mesh of its
    world-space triangles (analytic spheres and planes become their tessellations), every
    material inline.  `scene_from_dict(scene_to_dict(s))` gives the same triangles, camera and
    lights, so a saved scene reproduces any mask exactly."""

    def material(m: Material) -> dict:
        # roughness (and the lens keys below) only where set: older files stay as they were
        return {"ambient": m.ambient.tolist(), "diffuse": m.diffuse.tolist(),
                "specular": m.specular.tolist(), "shininess": m.shininess,
                "reflectivity": m.reflectivity, "transparency": m.transparency, "ior": m.ior,
                "emission": m.emission.tolist(),
                **({"roughness": m.roughness} if m.roughness else {}),
                **({} if m.texture is None else {"texture": texture(m.texture)})}

    def texture(t) -> dict:
        # its file (and image): read again on load, so the texels are the file's
        if not t.file:
            raise SceneError("texture", "a texture made in code has no file: save_scene "
                                        "writes a texture as the file it was read from")
        return {"file": t.file, **({} if t.image is None else {"image": t.image}),
                "wrap_s": t.wrap_s, "wrap_t": t.wrap_t, "filter": t.filter}

    def light(lt) -> dict:
        # the shadow switches only where off: files without them stay as they were
        out = {"color": lt.color.tolist(), "intensity": lt.intensity,
               **({} if lt.shadows else {"shadows": False})}
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
    if cam.matrix_form:   # the form it was given in (the look-at keys are derived from it)
        view = {"fx": cam.fx, "fy": cam.fy, "cx": cam.cx, "cy": cam.cy,
                "camera_to_world": cam.camera_to_world.tolist()}
    else:
        view = {"eye": cam.eye.tolist(), "target": cam.target.tolist(),
                "up": cam.up.tolist(), "fov_y": cam.fov_y}
    return {
        "name": scene.name,
        "ambient": scene.ambient.tolist(),
        "image": {"width": int(scene.width), "height": int(scene.height),
                  "background": scene.background.tolist()},
        "camera": {**view, "near": cam.near,
                   **({"aperture": cam.aperture} if cam.aperture else {}),
                   **({} if cam.focus_distance is None
                      else {"focus_distance": cam.focus_distance})},
        "render": {"max_depth": int(scene.max_depth)},
        "lights": [light(lt) for lt in scene.lights],
        "objects": [{"type": "mesh", "name": o.name, "vertices": o.vertices.tolist(),
                     "faces": o.faces.tolist(), "material": material(o.material),
                     **({} if o.uv is None else {"uv": o.uv.tolist()}),
                     **({} if o.colors is None else {"colors": o.colors.tolist()}),
                     **({} if o.category is None else {"category": o.category}),
                     **{k: False for k in ("cast_shadows", "receive_shadows")
                        if not getattr(o, k)}}
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
