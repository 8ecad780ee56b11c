"""Task: a ray against a plane (in 2D: a line), the lecture's first intersection."""

import numpy as np


def intersect(origin, direction, point, normal):
    """The ray parameter λ where the ray o + λ·r meets the plane through a with normal n.

    Inputs: origin o, direction r, point a on the plane and normal n, each a sequence of 2
    (a line in the plane) or 3 numbers; r and n need not be unit length.
    Output: λ as a float, the smallest λ > 0 with x(λ) on the plane, or None for a miss.

    Hesse normal form: n·x = d with d = n·a.  Put the ray in:
        n·(o + λ r) = d   =>   λ = (d − n·o) / (n·r)
    The ray misses when n·r = 0 (it runs parallel to the plane, even inside it) or when
    λ <= 0 (the plane lies behind the origin, or the origin lies on it: a ray is a half-line).

    >>> intersect((5, 1), (-1, 3), (2, 2), (1, -1))   # the lecture's exercise: x(1) = (4, 4)
    1.0
    """
    o, r = np.asarray(origin, float), np.asarray(direction, float)
    a, n = np.asarray(point, float), np.asarray(normal, float)
    n_dot_r = float(n @ r)
    if n_dot_r == 0.0:
        return None
    lam = float(n @ (a - o)) / n_dot_r
    return lam if lam > 0.0 else None
