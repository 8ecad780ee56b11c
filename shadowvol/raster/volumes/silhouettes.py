"""Silhouette edges by the multiplicity rule, on the CPU (numpy, float64).

Surfaces are two-sided (CONVENTIONS.md), so EVERY triangle occludes, whatever its winding.  Give
each triangle its own shadow volume, bounded by the triangle oriented to face the light (the near
cap), one side quad per edge, and the triangle projected to infinity (the far cap); the stencil
then counts how many triangles lie between a point and the light.  Summed over all triangles,
the side quads on a shared edge cancel or add up: triangle T with opposite vertex c contributes
sign(det[b - a, c - a, L - a]) to its edge (a, b), a < b (+1: T wound a, b, c faces the light, so
its light-facing orientation runs a -> b).  The edge's multiplicity m is the sum; it emits |m|
quads along the edge as the light-facing triangles run it (a -> b if m > 0).  Nothing assumes a closed, manifold or
consistently wound mesh: border edges have one term, non-manifold edges three or more.

The sign of a triangle is computed ONCE (as wound) and each edge term is that sign times the
edge's parity in the winding (see `topology`), so sides and caps always agree, even for a
triangle nearly edge-on to the light, and the volumes stay closed.

Lights are homogeneous points L4 = (L, 1) for point and spot lights and (-direction, 0) for a
directional light; "L - a" is L4.xyz - L4.w a, and a vertex V extrudes to (V L4.w - L4.xyz, 0).
"""

from __future__ import annotations

import numpy as np

from shadowvol.raster.volumes.topology import Topology


def triangle_signs(vertices: np.ndarray, faces: np.ndarray, light4: np.ndarray) -> np.ndarray:
    """(m,) int8: +1 if triangle (v0, v1, v2) as wound faces the light, -1 if it faces away,
    0 if the light lies in its plane (a volume of no thickness: no sides, no caps).

    vertices : (k, 3) float64; faces : (m, 3) int64; light4 : (4,) float64.
    """
    v0, v1, v2 = (vertices[faces[:, i]] for i in range(3))
    return _signs(np.cross(v1 - v0, v2 - v0), v0, light4)


def topology_signs(topology: Topology, light4: np.ndarray) -> np.ndarray:
    """`triangle_signs(topology.vertices, topology.faces, light4)`, bit for bit (the same
    float64 operations on the same numbers), from the normals and first corners the topology
    keeps: per light only the dot products remain."""
    normal, v0 = topology.face_frames
    return _signs(normal, v0, light4)


def _signs(normal: np.ndarray, v0: np.ndarray, light4: np.ndarray) -> np.ndarray:
    to_light = light4[:3] - light4[3] * v0
    return np.sign(np.einsum("ij,ij->i", normal, to_light)).astype(np.int8)


def edge_multiplicity(topology: Topology, signs: np.ndarray) -> np.ndarray:
    """(e,) int64: the multiplicity of every edge, sum over its triangles of sign * parity."""
    terms = signs[topology.inc_face].astype(np.int64) * topology.inc_parity
    return np.bincount(topology.inc_edge, weights=terms,
                       minlength=len(topology.edges)).astype(np.int64)


def extrude(points: np.ndarray, light4: np.ndarray) -> np.ndarray:
    """(n, 3) -> (n, 4) float64: each point sent to infinity away from the light (w = 0)."""
    return np.concatenate([points * light4[3] - light4[:3], np.zeros((len(points), 1))], axis=1)


def side_quads(topology: Topology, multiplicity: np.ndarray, light4: np.ndarray,
               unextruded: bool = False) -> np.ndarray:
    """(q, 4, 4) float64 homogeneous corners of every side quad, |m| copies per edge.

    For an edge that the light-facing triangles run s -> e (s, e = a, b if m > 0, else b, a)
    the quad is (e, 1), (s, 1), (s extruded, 0), (e extruded, 0): wound so that its normal
    points out of the volume, as the near cap's (the light-facing triangle) and the far cap's
    (that triangle reversed, at infinity) do.  Outward faces seen from the eye are front faces.
    `unextruded`: the w = 0 corners hold s and e themselves (`extrude_rows` extrudes them),
    for a caller that extrudes them in float32 exactly as the far caps' shaders do.
    """
    count = np.abs(multiplicity)
    which = np.repeat(np.arange(len(multiplicity)), count)
    a, b = topology.edges[which, 0], topology.edges[which, 1]
    forward = multiplicity[which] > 0
    start = topology.vertices[np.where(forward, a, b)]
    end = topology.vertices[np.where(forward, b, a)]
    ones = np.ones((len(which), 1))
    if unextruded:
        zeros = np.zeros((len(which), 1))
        far_start, far_end = (np.concatenate([p, zeros], axis=1) for p in (start, end))
    else:
        far_start, far_end = extrude(start, light4), extrude(end, light4)
    return np.stack([np.concatenate([end, ones], axis=1), np.concatenate([start, ones], axis=1),
                     far_start, far_end], axis=1)


def extrude_rows(corners: np.ndarray, light4: np.ndarray) -> np.ndarray:
    """(n, 4) float64 corners of `side_quads(..., unextruded=True)` -> those of
    `side_quads(...)`, bit for bit: each w = 0 row's point extruded (`extrude`)."""
    out = corners.copy()
    far = corners[:, 3] == 0.0
    out[far, :3] = corners[far, :3] * light4[3] - light4[:3]
    return out


def quads_to_triangles(quads: np.ndarray) -> np.ndarray:
    """(q, 4, 4) -> (2q * 3, 4): each quad (p0, p1, p2, p3) as triangles (p0, p1, p2) and
    (p0, p2, p3), keeping its orientation."""
    return quads[:, [0, 1, 2, 0, 2, 3]].reshape(-1, 4)
