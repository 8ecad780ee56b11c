"""The triangles every backend traces, and the backends' interface (`raytrace.backends`).

    closest_hit(origins, directions, tmax=None) -> Hits(t, tri)
    occluded(origins, directions, tmax=None)    -> (n,) bool
"""

from __future__ import annotations

from typing import NamedTuple, Protocol

import numpy as np

from .intersect import dot
from .tolerances import cross_rows, error_weight, norm_rows, sliver_edges


class Hits(NamedTuple):
    """Closest hits of n rays.

    t   : (n,) float, the dtype of the rays' origins: distance along the ray in units of
          |direction|; np.inf for a miss
    tri : (n,) int64, index of the hit triangle in `faces`; -1 for a miss
    """

    t: np.ndarray
    tri: np.ndarray


class TriangleBackend(Protocol):
    normals: np.ndarray  # (M, 3) float64 unit face normals, plane_d (M,): see TriangleSet
    plane_d: np.ndarray

    def closest_triangle(self, origins: np.ndarray, directions: np.ndarray,
                         tmax: np.ndarray | float | None = None, parallel: bool = True
                         ) -> np.ndarray: ...

    def closest_hit(self, origins: np.ndarray, directions: np.ndarray,
                    tmax: np.ndarray | float | None = None, parallel: bool = True) -> Hits: ...

    def occluded(self, origins: np.ndarray, directions: np.ndarray,
                 tmax: np.ndarray | float | None = None, parallel: bool = True
                 ) -> np.ndarray: ...

    def first_hit(self, origins: np.ndarray, directions: np.ndarray,
                  tmax: np.ndarray | float | None = None) -> Hits: ...

    def occluded_leaving(self, origins: np.ndarray, directions: np.ndarray,
                         tmax: np.ndarray, own: np.ndarray) -> np.ndarray: ...


class TriangleSet:
    """The triangles a backend traces, with what every backend needs in float64.

    vertices : (N, 3) float64;  faces : (M, 3) int64.
    normals  : (M, 3) float64 unit face normals by winding, (b − a) × (c − a) normalised
               (zero for degenerate triangles);  plane_d : (M,) float64, normals · a.
    weight   : (M,) float64, `tolerances.error_weight`;  fragile : (M,) bool,
               `tolerances.is_sliver` (what the masks need per triangle).
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray):
        self.vertices = np.ascontiguousarray(vertices, dtype=np.float64)
        self.faces = np.ascontiguousarray(faces, dtype=np.int64)
        tri = self.vertices[self.faces]
        e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
        n = cross_rows(e1, e2)
        area2 = norm_rows(n)
        length = area2[:, None]
        self.normals = np.divide(n, length, out=np.zeros_like(n), where=length > 0)
        self.plane_d = dot(self.normals, tri[:, 0])
        # what the masks need per triangle (`raytrace.tolerances`), from the same corners
        self.weight = error_weight(self.normals, tri)
        self.fragile = sliver_edges(e1, e2, tri[:, 2] - tri[:, 1], area2)  # = is_sliver(tri)

    def __len__(self) -> int:
        return len(self.faces)

    def refine(self, origins: np.ndarray, directions: np.ndarray, tri: np.ndarray) -> np.ndarray:
        """Distance t (n,) to the plane of triangle `tri` (n,) int (-1 = miss -> inf): the
        ray–plane formula, in the dtype of `origins` (float32 or float64), whatever precision
        chose the triangle."""
        dtype = np.float32 if origins.dtype == np.float32 else np.float64
        t = np.full(len(tri), np.inf, dtype)
        hit = np.flatnonzero(tri >= 0)
        k = tri[hit]
        n = self.normals[k].astype(dtype, copy=False)
        with np.errstate(divide="ignore", invalid="ignore"):
            th = (self.plane_d[k].astype(dtype) - dot(n, origins[hit])) / dot(n, directions[hit])
        t[hit] = np.where(np.isfinite(th), th, 0.0)  # a ray inside a triangle's plane: t ~ 0
        return t
