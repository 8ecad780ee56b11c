"""Task: the silhouette edges of a triangle mesh seen from a point light, with multiplicities."""

import numpy as np


def silhouette_edges(vertices, faces, light):
    """Every edge of the mesh that bounds a shadow volume, with its multiplicity.

    Inputs: vertices, a list of (x, y, z); faces, a list of (i, j, k) vertex indices (the
    triangles, in any winding: every triangle is a two-sided occluder); light, the point
    light's position L.
    Output: a dict {(a, b): m} over the edges with m != 0, keyed by the edge's vertex indices
    with a < b.

    The multiplicity rule: each triangle T = (i, j, k) as wound has the sign
        s(T) = sign( ((v_j − v_i) × (v_k − v_i)) · (L − v_i) )
    (+1: the light sees the side it is wound counter-clockwise on; −1: the other side; 0: the
    light lies in its plane).  T adds to each of its edges, as wound (i, j), (j, k), (k, i),
    +s(T) when the edge runs from the smaller index to the larger, −s(T) when it runs the other
    way.  An edge's multiplicity m is the sum over its triangles: 0 inside a smooth, lit or
    unlit part of a closed mesh, ±1 on a border, ±2 on the silhouette of a closed mesh (both
    sides of the surface cast).  m > 0 means the quads run a -> b.

    >>> silhouette_edges([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(0, 1, 2)], (0, 0, 5))
    {(0, 1): 1, (1, 2): 1, (0, 2): -1}
    """
    v = np.asarray(vertices, float)
    L = np.asarray(light, float)
    out = {}
    for i, j, k in faces:
        sign = int(np.sign(np.cross(v[j] - v[i], v[k] - v[i]) @ (L - v[i])))
        for s, e in ((i, j), (j, k), (k, i)):
            key = (min(s, e), max(s, e))
            out[key] = out.get(key, 0) + (sign if s < e else -sign)
    return {key: m for key, m in out.items() if m != 0}
