"""What a mesh file says about its surfaces: UVs, base-colour textures, base colours and vertex
colours (glTF/GLB, OBJ + MTL, PLY/OFF vertex colours), and the one warning naming what is not
read.

trimesh reads the geometry, the UVs and vertex colours; the materials are read here from the
file itself, since trimesh keeps neither a glTF sampler nor exact colour factors (it rounds
them to 8 bits), and drops a texture it cannot read without a word: here a missing or
unreadable texture is a SceneError naming the file.  UVs are stored in glTF's convention (v
down, the image's top row at v = 0): trimesh turns every format's into OBJ's (v up), which is
turned back here.  Vertex colours are linear RGB: glTF's COLOR_0 is linear by the spec; the
8-bit colours of PLY, OFF and OBJ files are display (sRGB) colours and are decoded.
"""

from __future__ import annotations

import base64
import binascii
import io
import json
import os
import struct
import warnings
from pathlib import Path, PurePosixPath
from typing import NamedTuple
from urllib.parse import unquote

import numpy as np

from shadowvol.checks import SceneError
from shadowvol.errors import IgnoredMaterial, short_path
from shadowvol.textures import FILTERS, GLTF_FILTERS, GLTF_WRAPS, WRAPS, Texture

MAX_TEXTURE_FILE_BYTES = 1 << 28   # the size limit of each texture or MTL file
MAX_GLTF_FILE_BYTES = 1 << 30      # of a glTF file or buffer read for its images (a mesh's)
# glTF material features not read (what the warning names)
_GLTF_IGNORED = ("normalTexture", "occlusionTexture", "emissiveTexture")
# MTL statements that name maps not read (any other map_ but map_Kd too)
_MTL_MAPS = ("bump", "disp", "decal", "refl", "norm")


class Surface(NamedTuple):
    """What one part of a mesh file says about its surface (each None where it says nothing).

    diffuse : (3,) float64 linear base colour (glTF's baseColorFactor, MTL's Kd)
    texture : a `Texture`;  uv : (n, 2) float64 (glTF's convention);  colors : (n, 3) float64
    """

    diffuse: np.ndarray | None = None
    texture: Texture | None = None
    uv: np.ndarray | None = None
    colors: np.ndarray | None = None


def warn_ignored(path: Path, ignored) -> None:
    """The one warning line naming the file and what of its materials is not read."""
    if ignored:
        warnings.warn(IgnoredMaterial(
            f"{short_path(path)}: not read: {', '.join(sorted(set(ignored)))} (only the base "
            "colour, its texture and vertex colours are; shadows treat every surface as "
            "opaque)"), stacklevel=2)


def decode_image(data: bytes, what: str, key: str) -> np.ndarray:
    """(h, w, 3) uint8 sRGB codes of an image file's bytes (PNG, JPEG, ... by Pillow)."""
    from PIL import Image  # deferred: only textured meshes need it

    try:
        with Image.open(io.BytesIO(data)) as image:
            image.load()
            rgb = image.convert("RGBA" if "A" in image.getbands() else "RGB")
    except Image.UnidentifiedImageError:
        raise SceneError(key, f"cannot read texture {what}: not an image format Pillow "
                              "reads") from None
    except Exception as exc:  # Pillow raises many types for a bad image
        raise SceneError(key, f"cannot read texture {what}: {type(exc).__name__}: "
                              f"{exc}") from None
    return np.ascontiguousarray(np.asarray(rgb)[..., :3], np.uint8)


def read_texture_file(path: Path, key: str, read, **sampler) -> Texture:
    """The Texture of the image file `path`, its bytes by `read(path, max_bytes, key, what)`
    (`scenefile_mesh.read_regular_file`: a regular file under the size limit)."""
    if not path.is_file() and not path.exists():
        raise SceneError(key, f"texture file not found: {short_path(path)}")
    data = read(path, MAX_TEXTURE_FILE_BYTES, key, f"texture {short_path(path)}")
    return Texture(decode_image(data, short_path(path), key), file=os.path.abspath(path),
                   **sampler)


def vertex_colours(mesh, linear: bool) -> np.ndarray | None:
    """(n, 3) float64 linear vertex colours of a trimesh mesh, or None: ColorVisuals' 8-bit
    vertex colours, or a textured glTF's COLOR_0 (`vertex_attributes['color']`); `linear`:
    the codes are linear (glTF), else sRGB."""
    visual = mesh.visual
    raw = None
    if getattr(visual, "kind", None) == "vertex":
        raw = np.asarray(visual.vertex_colors)
    elif "color" in getattr(visual, "vertex_attributes", {}):
        raw = np.asarray(visual.vertex_attributes["color"])
    if raw is None or raw.ndim != 2 or raw.shape[1] < 3 or len(raw) != len(mesh.vertices):
        return None
    rgb = raw[:, :3]
    if rgb.dtype.kind == "f":
        return np.clip(rgb.astype(np.float64), 0.0, None)
    scale = float(np.iinfo(rgb.dtype).max)
    c = rgb.astype(np.float64) / scale
    if linear:
        return c
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def trimesh_uv(mesh) -> np.ndarray | None:
    """(n, 2) float64 UVs of a trimesh mesh in glTF's convention (v down), or None."""
    uv = getattr(mesh.visual, "uv", None)
    if uv is None or len(uv) != len(mesh.vertices):
        return None
    uv = np.array(uv, np.float64).reshape(-1, 2)
    uv[:, 1] = 1.0 - uv[:, 1]
    return uv


# ---------------------------------------------------------------------------------------------
# glTF / GLB
# ---------------------------------------------------------------------------------------------

def gltf_primitives(document: dict) -> list[tuple[int, dict]]:
    """(mesh index, primitive) of every primitive trimesh makes a geometry of, in its order:
    the file's meshes and their primitives in order, modes points, lines, triangles and strips
    (trimesh skips the others)."""
    out = []
    for m, mesh in enumerate(document.get("meshes", [])):
        for prim in mesh.get("primitives", []) if isinstance(mesh, dict) else []:
            if isinstance(prim, dict) and prim.get("mode", 4) in (0, 1, 4, 5):
                out.append((m, prim))
    return out


def gltf_surfaces(path: Path, document: dict, loaded, key: str, read) -> dict:
    """geometry name -> Surface of every geometry of a loaded glTF/GLB (a trimesh.Scene), and
    the one warning for what is not read.  `document` is the file's JSON; `read` reads a
    texture file (`read_texture_file`)."""
    names = list(loaded.geometry)
    prims = gltf_primitives(document)
    materials = document.get("materials", [])
    textured = any(_base_texture(m) is not None for m in materials if isinstance(m, dict))
    aligned = len(prims) == len(names) and all(
        _count(document, p) in (None, len(getattr(loaded.geometry[n], "vertices", ())))
        for n, (_, p) in zip(names, prims))
    if textured and not aligned:
        raise SceneError(key, f"{short_path(path)}: cannot tell which of its primitives each "
                              "mesh trimesh read is, so not which texture it has")
    ignored, out, made = [], {}, {}
    kept = {}

    def once(file, *args):   # each file read once (the GLB itself holds its images)
        if file not in kept:
            kept[file] = read(file, *args)
        return kept[file]

    for name, (_, prim) in zip(names, prims) if aligned else ():
        mesh = loaded.geometry[name]
        index = prim.get("material")
        material = materials[index] if isinstance(index, int) and \
            0 <= index < len(materials) else None
        diffuse = texture = None
        if isinstance(material, dict):
            ignored += _gltf_ignored(material)
            pbr = material.get("pbrMetallicRoughness") or {}
            factor = pbr.get("baseColorFactor")
            if isinstance(factor, list) and len(factor) >= 3:
                diffuse = np.asarray(factor[:3], np.float64)
            if index not in made:
                made[index] = _gltf_texture(path, document, material, key, ignored, once)
            texture = made[index]
        uv = trimesh_uv(mesh) if texture is not None else None
        if texture is not None and uv is None:
            ignored.append("a baseColorTexture without TEXCOORD_0")
            texture = None
        out[name] = Surface(diffuse, texture, uv, vertex_colours(mesh, linear=True))
    warn_ignored(path, ignored)
    return out


def _count(document: dict, prim: dict) -> int | None:
    try:
        return int(document["accessors"][prim["attributes"]["POSITION"]]["count"])
    except (KeyError, IndexError, TypeError, ValueError):
        return None


def _base_texture(material: dict) -> dict | None:
    info = (material.get("pbrMetallicRoughness") or {}).get("baseColorTexture")
    return info if isinstance(info, dict) else None


def _gltf_ignored(material: dict) -> list[str]:
    out = [name for name in _GLTF_IGNORED if name in material]
    pbr = material.get("pbrMetallicRoughness") or {}
    if "metallicRoughnessTexture" in pbr:
        out.append("metallicRoughnessTexture")
    if material.get("alphaMode", "OPAQUE") != "OPAQUE":
        out.append(f"alphaMode {material['alphaMode']}")
    if any(x for x in material.get("emissiveFactor", []) if isinstance(x, (int, float))):
        out.append("emissiveFactor")
    out += [f"extension {name}" for name in material.get("extensions", {}) or {}]
    base = _base_texture(material) or {}
    out += [f"baseColorTexture extension {name}" for name in base.get("extensions", {}) or {}]
    if base.get("texCoord", 0) != 0:
        out.append(f"baseColorTexture texCoord {base['texCoord']} (TEXCOORD_0 only)")
    return out


def _gltf_texture(path: Path, document: dict, material: dict, key: str,
                  ignored: list, read) -> Texture | None:
    """The base-colour Texture of a glTF material (None: it has none, or one not read, named
    in `ignored`), its sampler's wrap and filter; the image trimesh decoded, or a SceneError
    naming the image that cannot be read."""
    base = _base_texture(material)
    if base is None or base.get("texCoord", 0) != 0:
        return None
    try:
        texture = document["textures"][base["index"]]
        source = texture.get("source")
        image = document["images"][source] if source is not None else None
        sampler = document["samplers"][texture["sampler"]] if "sampler" in texture else {}
    except (KeyError, IndexError, TypeError):
        raise SceneError(key, f"{short_path(path)}: its baseColorTexture {base.get('index')} "
                              "names a texture, image or sampler that is not there") from None
    if image is None:
        ignored.append("a baseColorTexture without an image (an extension's)")
        return None
    if image.get("mimeType") == "image/ktx2":
        ignored.append("KTX2 textures")
        return None
    wrap = {"wrap_s": GLTF_WRAPS.get(sampler.get("wrapS", 10497)),
            "wrap_t": GLTF_WRAPS.get(sampler.get("wrapT", 10497))}
    filt = GLTF_FILTERS.get(sampler.get("magFilter", sampler.get("minFilter", 9729)))
    if None in wrap.values() or filt is None:
        raise SceneError(key, f"{short_path(path)}: sampler {texture.get('sampler')}: unknown "
                              f"wrap or filter code in {sampler}")
    uri = image.get("uri")
    if isinstance(uri, str) and not uri.startswith("data:"):
        return read_texture_file(path.parent / unquote(uri), key, read, filter=filt, **wrap)
    return read_gltf_image(path, source, key, read, filter=filt, **wrap)


def read_gltf_image(path: Path, index: int, key: str, read, **sampler) -> Texture:
    """The Texture of image `index` of the glTF/GLB file `path` held in the file itself (a
    bufferView or a data URI); `read` reads files (`read_texture_file`)."""
    data = read(path, MAX_GLTF_FILE_BYTES, key)
    what = f"image {index} of {short_path(path)}"
    try:
        document, chunk = _gltf_chunks(path, data)
        image = document["images"][index]
        if "bufferView" in image:
            view = document["bufferViews"][image["bufferView"]]
            buffer = _gltf_buffer(path, document, chunk, view.get("buffer", 0), key, read)
            start = view.get("byteOffset", 0)
            blob = buffer[start:start + view["byteLength"]]
            if len(blob) != view["byteLength"]:
                raise ValueError("its bufferView runs past its buffer")
        else:
            blob = _data_uri(image["uri"])
    except (KeyError, IndexError, TypeError, ValueError, struct.error,
            binascii.Error) as exc:
        raise SceneError(key, f"cannot read texture {what}: {exc}") from None
    return Texture(decode_image(blob, what, key), file=os.path.abspath(path), image=index,
                   **sampler)


def _gltf_chunks(path: Path, data: bytes) -> tuple[dict, bytes]:
    """A glTF/GLB file's JSON and (GLB) its BIN chunk (b"" if none)."""
    if path.suffix.lower() != ".glb":
        return json.loads(data), b""
    length = struct.unpack_from("<I", data, 12)[0]
    document = json.loads(data[20:20 + length])
    at = 20 + length
    if len(data) >= at + 8 and data[at + 4:at + 8] == b"BIN\0":
        return document, data[at + 8:at + 8 + struct.unpack_from("<I", data, at)[0]]
    return document, b""


def _gltf_buffer(path: Path, document: dict, chunk: bytes, index: int, key: str,
                 read) -> bytes:
    uri = document["buffers"][index].get("uri")
    if uri is None:
        return chunk           # a GLB's own BIN chunk
    if uri.startswith("data:"):
        return _data_uri(uri)
    return read(path.parent / unquote(uri), MAX_GLTF_FILE_BYTES, key)


def _data_uri(uri: str) -> bytes:
    head, _, body = uri.partition(",")
    if not head.startswith("data:") or not head.endswith(";base64"):
        raise ValueError("not a base64 data URI")
    return base64.b64decode(body, validate=True)


def texture_from_dict(value, key: str, base_dir: Path, read) -> Texture:
    """A material's `texture` table of a scene file (as `save_scene` writes it): `file` (an
    image file, or with `image` a glTF/GLB file and the index of an image it holds) and the
    sampler's `wrap_s`, `wrap_t`, `filter`."""
    if not isinstance(value, dict):
        raise SceneError(key, f"expected a table, got {type(value).__name__}")
    unknown = set(value) - {"file", "image", "wrap_s", "wrap_t", "filter"}
    if unknown:
        raise SceneError(key, f"unknown key {sorted(unknown)[0]!r}")
    file, image = value.get("file"), value.get("image")
    if not isinstance(file, str) or not file:
        raise SceneError(f"{key}.file", "expected a file path")
    if image is not None and (isinstance(image, bool) or not isinstance(image, int)):
        raise SceneError(f"{key}.image", f"expected an image index, got {image!r}")
    sampler = {k: value[k] for k in ("wrap_s", "wrap_t", "filter") if k in value}
    for k, v in sampler.items():
        allowed = FILTERS if k == "filter" else WRAPS
        if v not in allowed:
            raise SceneError(f"{key}.{k}", f"expected one of {', '.join(allowed)}, got {v!r}")
    if image is None:
        return read_texture_file(base_dir / file, key, read, **sampler)
    return read_gltf_image(base_dir / file, image, key, read, **sampler)


# ---------------------------------------------------------------------------------------------
# OBJ + MTL
# ---------------------------------------------------------------------------------------------

def obj_materials(path: Path, data: bytes, key: str, read) -> tuple[dict[str, Surface], list]:
    """material name -> Surface (Kd, map_Kd) of the MTL files an OBJ file names (`mtllib`),
    and what of them is not read (for `warn_ignored`).  A missing MTL or texture file, or an
    unreadable image, is a SceneError naming it; `read` reads a file (`read_texture_file`)."""
    out, ignored = {}, []
    for line in data.decode("utf-8", "replace").splitlines():
        words = line.split(None, 1)
        if len(words) < 2 or words[0] != "mtllib":
            continue
        mtl = path.parent / words[1].strip()
        if not mtl.exists():
            raise SceneError(key, f"material file not found: {short_path(mtl)} "
                                  f"(mtllib of {short_path(path)})")
        text = read(mtl, MAX_TEXTURE_FILE_BYTES, key).decode("utf-8", "replace")
        out.update(_mtl(mtl, text, key, ignored, read))
    return out, ignored


def _mtl(mtl: Path, text: str, key: str, ignored: list, read) -> dict[str, Surface]:
    out, name, kd, texture = {}, None, None, None

    def done():
        if name is not None:
            out[name] = Surface(kd, texture)

    for number, line in enumerate(text.splitlines(), 1):
        words = line.split()
        if not words:
            continue
        word = words[0].lower()
        if word == "newmtl":
            done()
            name, kd, texture = " ".join(words[1:]), None, None
        elif word == "kd" and len(words) >= 4:
            try:
                kd = np.array([float(x) for x in words[1:4]])
            except ValueError:
                raise SceneError(key, f"{short_path(mtl)}: line {number}: Kd needs three "
                                      f"numbers, got {' '.join(words[1:4])!r}") from None
        elif word == "map_kd" and len(words) >= 2:
            if len(words) > 2:
                ignored.append("map_Kd options")
            texture = read_texture_file(mtl.parent / PurePosixPath(words[-1]), key, read)
        elif word.startswith("map_") or word in _MTL_MAPS:
            ignored.append(words[0])
    done()
    return out
