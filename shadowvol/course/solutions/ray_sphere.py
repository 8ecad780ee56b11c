"""Task: a ray against a sphere (in 2D: a circle)."""

import math

import numpy as np


def intersect(origin, direction, center, radius):
    """The smallest λ > 0 where the ray o + λ·r meets the sphere |x − c| = R.

    Inputs: origin o, direction r (not necessarily unit length), center c: sequences of 2 or 3
    numbers; radius R > 0.
    Output: λ as a float, or None for a miss.

    |o + λ r − c|² = R² is the quadratic a λ² + b λ + c' = 0 with
        a = r·r,   b = 2 r·(o − c),   c' = |o − c|² − R²,   Δ = b² − 4 a c'.
    Δ < 0: a miss.  Δ = 0: the ray touches the sphere (a grazing ray), one hit.  Δ > 0: two
    roots λ1 <= λ2 = (−b ∓ √Δ) / 2a.  The hit is λ1 when λ1 > 0 (the ray starts outside, in
    front of the sphere), else λ2 when λ2 > 0 (it starts inside), else None (behind it).

    >>> intersect((0, 0, -5), (0, 0, 1), (0, 0, 0), 1.0)
    4.0
    """
    o, r, c = (np.asarray(v, float) for v in (origin, direction, center))
    oc = o - c
    a = float(r @ r)
    b = 2.0 * float(r @ oc)
    c2 = float(oc @ oc) - radius * radius
    disc = b * b - 4.0 * a * c2
    if disc < 0.0:
        return None
    root = math.sqrt(disc)
    near, far = (-b - root) / (2.0 * a), (-b + root) / (2.0 * a)
    if near > 0.0:
        return near
    if far > 0.0:
        return far
    return None
