"""Task: the planar projected shadow matrix (Blinn 1988, "Me and my (fake) shadow")."""

import numpy as np


def projection_matrix(plane_point, plane_normal, light):
    """The 4 x 4 matrix M that projects points from the light onto a plane.

    Inputs: plane_point a point of the receiving plane and plane_normal its normal (any length,
    not zero), 3 numbers each; light, the homogeneous light L = (x, y, z, w): w = 1 for a point
    light at (x, y, z), w = 0 for a directional light coming FROM the direction (x, y, z).
    Output: M as 4 rows of 4 numbers, for column vectors: X' = M X, then divide by X'[3].

    With the unit normal n̂ = n / |n| the plane is P = (n̂, −n̂·plane_point) (the points X with
    P·X = 0), and
        M = sign(P·L) · ((P·L) I − L Pᵀ)
    M X = (P·L) X − (P·X) L lies on the line through L and X and on the plane.  The factor
    sign(P·L) makes w positive for a real shadow, whichever side of the plane the light is on
    (GL clips w < 0).

    >>> [[float(x) for x in row] for row in projection_matrix((0, 0, 0), (0, 1, 0), (0, 2, 0, 1))]
    [[2.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 2.0, 0.0], [0.0, -1.0, 0.0, 2.0]]
    """
    n = np.asarray(plane_normal, float)
    n = n / np.linalg.norm(n)
    P = np.append(n, -float(n @ np.asarray(plane_point, float)))
    L = np.asarray(light, float)
    p_dot_l = float(P @ L)
    M = p_dot_l * np.eye(4) - np.outer(L, P)
    return np.sign(p_dot_l) * M
