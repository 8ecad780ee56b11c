"""Edge topology of a triangle soup, computed once per mesh: welded vertices and every edge with
all the triangles on it.

Positions are welded EXACTLY (identical float64 coordinates become one vertex).  Real meshes
duplicate vertices along seams with identical coordinates (the teapot's Bezier patch seams, UV
seams); exact welding joins those without moving any vertex, so the welded positions are bit for
bit the positions the depth pass draws, and signs computed from either agree.

An edge is a pair of welded vertex indices (a, b) with a < b.  Each triangle contributes one
*incidence* per edge: (edge, triangle, opposite vertex, parity).  Any number of triangles may share
an edge: 1 on an open border, 2 on a manifold, 3 or more on a non-manifold edge.  `parity` is +1
when the triangle, as wound in `faces`, runs a -> b and -1 when it runs b -> a, so the edge's
contribution sign(det[b - a, c - a, L - a]) equals parity * (the sign of the whole triangle as
wound), computed once per triangle.  Triangles whose corners weld together (zero-length edges) add
no edge and have sign 0.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

INDEX = np.int32         # the dtype of every index a topology holds
INDEX_LIMIT = 2 ** 31


@dataclass(frozen=True, eq=False)
class Topology:
    """
    vertices   : (k, 3) float64 welded positions
    remap      : (n,) int32, original vertex -> welded vertex
    faces      : (m, 3) int32, triangles on welded vertices, original winding
    edges      : (e, 2) int32, a < b, sorted
    inc_edge   : (i,) int32, the edge of each incidence, sorted ascending
    inc_face   : (i,) int32, its triangle
    inc_opposite : (i,) int32, the triangle's third (welded) vertex
    inc_parity : (i,) int8, +1 if the triangle runs a -> b, -1 if b -> a

    Indices are int32 (a mesh has fewer than 2^31 vertices and triangles: the rasterizer
    draws at most `geometry.MAX_TRIANGLES`): half the memory of int64, and numpy indexes
    with them as fast.
    """

    vertices: np.ndarray
    remap: np.ndarray
    faces: np.ndarray
    edges: np.ndarray
    inc_edge: np.ndarray
    inc_face: np.ndarray
    inc_opposite: np.ndarray
    inc_parity: np.ndarray

    @cached_property
    def face_frames(self) -> tuple[np.ndarray, np.ndarray]:
        """normals (m, 3) float64 = cross(v1 - v0, v2 - v0) of `faces` as wound (not unit), and
        origins (m, 3) float64 = v0: the light-independent part of every triangle's sign
        (`silhouettes.topology_signs`), computed on first use and kept (48 bytes a triangle)."""
        v0, v1, v2 = (self.vertices[self.faces[:, i]] for i in range(3))
        return np.cross(v1 - v0, v2 - v0), v0

    @property
    def triangles_per_edge(self) -> np.ndarray:
        """(e,) int64: 1 on open borders, 2 on manifold edges, 3+ on non-manifold edges."""
        return np.bincount(self.inc_edge, minlength=len(self.edges))

    @classmethod
    def build(cls, vertices: np.ndarray, faces: np.ndarray) -> "Topology":
        """From an (n, 3) float64 vertex array and (m, 3) int64 faces."""
        welded, remap = np.unique(np.asarray(vertices, np.float64), axis=0, return_inverse=True)
        if len(welded) >= INDEX_LIMIT or len(faces) * 3 >= INDEX_LIMIT:
            raise ValueError(f"{len(welded):,} vertices, {len(faces):,} triangles: a topology "
                             f"indexes them with int32, fewer than {INDEX_LIMIT:,}")
        remap = remap.reshape(-1).astype(INDEX)
        f = remap[np.asarray(faces, np.int64)]
        m = len(f)
        # the three directed edges of each triangle as wound, and the opposite corner
        start = f[:, [0, 1, 2]].reshape(-1)
        end = f[:, [1, 2, 0]].reshape(-1)
        opposite = f[:, [2, 0, 1]].reshape(-1)
        face = np.repeat(np.arange(m, dtype=INDEX), 3)
        keep = start != end
        start, end, opposite, face = start[keep], end[keep], opposite[keep], face[keep]
        parity = np.where(start < end, 1, -1).astype(np.int8)
        a, b = np.minimum(start, end), np.maximum(start, end)
        key = a.astype(np.int64) * len(welded) + b   # int64: up to k^2
        edge_keys, inc_edge = np.unique(key, return_inverse=True)
        edges = np.stack([edge_keys // len(welded), edge_keys % len(welded)],
                         axis=1).astype(INDEX)
        order = np.argsort(inc_edge, kind="stable")
        return cls(vertices=welded, remap=remap, faces=f, edges=edges,
                   inc_edge=inc_edge.reshape(-1)[order].astype(INDEX), inc_face=face[order],
                   inc_opposite=opposite[order], inc_parity=parity[order])
