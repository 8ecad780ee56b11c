"""What a glTF or GLB file says about itself, checked before trimesh reads it: its nodes form
trees (`check_node_tree`), and every buffer view and accessor lies inside the bytes it names
(`check_layout`), so that a broken file is one SceneError naming the glTF key, never
trimesh's bare `AssertionError` or an endless walk.  Only the file's JSON and the buffers'
sizes are looked at (a data URI's decoded length, a GLB's binary chunk, an external buffer's
file size); trimesh reads the bytes.
"""

from __future__ import annotations

import base64
import json
import os
import stat
import struct
from pathlib import Path

from shadowvol.scene import SceneError, shorten

# bytes of one component, by glTF componentType; components of one item, by accessor type
COMPONENT_BYTES = {5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4}
TYPE_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9,
                   "MAT4": 16}


def gltf_document(path: Path, data: bytes):
    """The JSON of a glTF or GLB file, or None when it cannot be read (trimesh says why)."""
    try:
        if path.suffix.lower() == ".glb":
            length = struct.unpack_from("<I", data, 12)[0]
            return json.loads(data[20:20 + length])
        return json.loads(data)
    except (ValueError, struct.error, RecursionError):
        return None


def check_node_tree(path: Path, document, key: str) -> None:
    """SceneError unless a glTF's nodes form trees, as the glTF spec requires: every child an
    index of a node, no node the child of two parents, none its own ancestor (a cycle, which
    trimesh would walk until its iteration limit, or not at all)."""
    nodes = document.get("nodes") if isinstance(document, dict) else None
    if not isinstance(nodes, list):
        return
    parent: dict[int, int] = {}
    for i, node in enumerate(nodes):
        children = node.get("children", []) if isinstance(node, dict) else []
        if not isinstance(children, list):
            raise SceneError(key, f"{path}: nodes[{i}].children: expected a list of node "
                                  f"indices, got {shorten(children)}")
        for child in children:
            if isinstance(child, bool) or not isinstance(child, int) or \
                    not 0 <= child < len(nodes):
                raise SceneError(key, f"{path}: nodes[{i}].children: {shorten(child)} is not "
                                      f"a node index (0..{len(nodes) - 1})")
            if child in parent:
                raise SceneError(key, f"{path}: nodes[{i}].children: node {child} is also a "
                                      f"child of node {parent[child]} (glTF nodes form trees)")
            parent[child] = i
    state = [0] * len(nodes)  # 0: not seen, 1: on the climb from `start`, 2: done
    for start in range(len(nodes)):  # climb to the root: each node once, however long
        climb, node = [], start
        while node is not None and state[node] == 0:
            state[node] = 1
            climb.append(node)
            node = parent.get(node)
        if node is not None and state[node] == 1:
            cycle = climb[climb.index(node):]  # the node, its parent, ... back to it
            chain = " -> ".join(map(str, [cycle[0], *reversed(cycle[1:]), cycle[0]]))
            raise SceneError(key, f"{path}: nodes[{cycle[0]}]: node {cycle[0]} is its own "
                                  f"ancestor (the node graph has a cycle: {chain})")
        for node in climb:
            state[node] = 2


def _whole(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def buffer_sizes(path: Path, document: dict, data: bytes) -> list[int | None]:
    """The bytes each of a glTF's `buffers` really holds: a data URI's decoded length, the
    GLB's binary chunk for a buffer without a URI, an external file's size; None where that
    cannot be told here (a missing file: trimesh says so)."""
    sizes: list[int | None] = []
    for i, buffer in enumerate(document.get("buffers") or []):
        uri = buffer.get("uri") if isinstance(buffer, dict) else None
        size = None
        if uri is None and i == 0 and path.suffix.lower() == ".glb":
            json_length = struct.unpack_from("<I", data, 12)[0]
            at = 20 + json_length
            if len(data) >= at + 8 and data[at + 4:at + 8] == b"BIN\0":
                size = struct.unpack_from("<I", data, at)[0]
        elif isinstance(uri, str) and uri.startswith("data:"):
            payload = uri.partition(",")[2]
            if ";base64" in uri.partition(",")[0]:
                try:
                    size = len(base64.b64decode(payload, validate=False))
                except ValueError:
                    size = None
        elif isinstance(uri, str):
            try:  # a regular file's size (a FIFO or a device: the resolver refuses it)
                st = os.stat(path.parent / uri)
                size = st.st_size if stat.S_ISREG(st.st_mode) else None
            except (OSError, ValueError):
                size = None
        sizes.append(size)
    return sizes


def check_layout(path: Path, document, data: bytes, key: str) -> None:
    """SceneError unless each buffer view lies inside its buffer and each accessor inside its
    view (what trimesh checks with bare asserts, or finds as a numpy reshape error)."""
    if not isinstance(document, dict):
        return
    views = document.get("bufferViews") or []
    sizes = buffer_sizes(path, document, data)
    for i, view in enumerate(views if isinstance(views, list) else []):
        if not isinstance(view, dict):
            continue
        b, length, offset = view.get("buffer"), view.get("byteLength"), view.get("byteOffset", 0)
        where = f"{path}: bufferViews[{i}]"
        if not (_whole(b) and 0 <= b < len(sizes)):
            raise SceneError(key, f"{where}.buffer: {shorten(b)} is not a buffer index "
                                  f"(the file has {len(sizes)} buffers)")
        if not (_whole(length) and length >= 1 and _whole(offset) and offset >= 0):
            raise SceneError(key, f"{where}: byteLength {shorten(length)} and byteOffset "
                                  f"{shorten(offset)} must be whole numbers >= 1 and >= 0")
        stride = view.get("byteStride")
        if stride is not None and not (_whole(stride) and 4 <= stride <= 252):
            raise SceneError(key, f"{where}.byteStride: must be 4..252 (glTF), got "
                                  f"{shorten(stride)}")
        if sizes[b] is not None and offset + length > sizes[b]:
            raise SceneError(key, f"{where}: bytes {offset}..{offset + length} reach past the "
                                  f"end of buffers[{b}] ({sizes[b]} bytes)")
    for i, accessor in enumerate(document.get("accessors") or []):
        if not isinstance(accessor, dict) or "bufferView" not in accessor:
            continue
        v, count = accessor.get("bufferView"), accessor.get("count")
        where = f"{path}: accessors[{i}]"
        if not (_whole(v) and 0 <= v < len(views)) or not isinstance(views[v], dict):
            raise SceneError(key, f"{where}.bufferView: {shorten(v)} is not a buffer view "
                                  f"index (the file has {len(views)})")
        item = COMPONENT_BYTES.get(accessor.get("componentType"), 0) * \
            TYPE_COMPONENTS.get(accessor.get("type"), 0)
        offset = accessor.get("byteOffset", 0)
        if not (item and _whole(count) and count >= 1 and _whole(offset) and offset >= 0):
            continue  # trimesh names an unknown type or count itself
        view = views[v]
        stride = view.get("byteStride") or item
        need = offset + (count - 1) * stride + item
        if need > view["byteLength"]:
            raise SceneError(key, f"{where}: {count} {accessor['type']} items of {item} bytes "
                                  f"from byte {offset} (stride {stride}) need {need} bytes, "
                                  f"bufferViews[{v}] has {view['byteLength']}")
