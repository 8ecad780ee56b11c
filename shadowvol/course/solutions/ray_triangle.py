"""Task: a ray against a triangle, with the hit's barycentric coordinates."""

import numpy as np


def intersect(origin, direction, a, b, c):
    """Where the ray o + λ·r meets the triangle (a, b, c), edges included.

    Inputs: origin o, direction r and the corners a, b, c, each a sequence of 3 numbers.
    Output: (λ, β, γ) as floats, with the hit p = o + λ r = a + β (b − a) + γ (c − a), i.e. the
    barycentric coordinates (α, β, γ) = (1 − β − γ, β, γ); or None for a miss.

    1. The plane: normal N = (b − a) × (c − a); λ = N·(a − o) / (N·r), a miss when N·r = 0 or
       λ <= 0.
    2. In the plane: with w = p − a, e1 = b − a, e2 = c − a, solve w = β e1 + γ e2:
           D = (e1·e1)(e2·e2) − (e1·e2)²
           β = ((e2·e2)(w·e1) − (e1·e2)(w·e2)) / D
           γ = ((e1·e1)(w·e2) − (e1·e2)(w·e1)) / D
    3. p is inside (or on an edge) when β >= 0, γ >= 0 and β + γ <= 1.

    >>> intersect((0.25, 0.25, 1), (0, 0, -1), (0, 0, 0), (1, 0, 0), (0, 1, 0))
    (1.0, 0.25, 0.25)
    """
    o, r = np.asarray(origin, float), np.asarray(direction, float)
    a, b, c = (np.asarray(v, float) for v in (a, b, c))
    e1, e2 = b - a, c - a
    normal = np.cross(e1, e2)
    n_dot_r = float(normal @ r)
    if n_dot_r == 0.0:
        return None
    lam = float(normal @ (a - o)) / n_dot_r
    if lam <= 0.0:
        return None
    w = o + lam * r - a
    d11, d12, d22 = float(e1 @ e1), float(e1 @ e2), float(e2 @ e2)
    w1, w2 = float(w @ e1), float(w @ e2)
    det = d11 * d22 - d12 * d12
    beta = (d22 * w1 - d12 * w2) / det
    gamma = (d11 * w2 - d12 * w1) / det
    if beta >= 0.0 and gamma >= 0.0 and beta + gamma <= 1.0:
        return lam, beta, gamma
    return None
