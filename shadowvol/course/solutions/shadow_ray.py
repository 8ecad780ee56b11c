"""Task: the shadow-ray test: is a point in shadow of a set of spheres?"""

import math

import numpy as np

# How far the shadow ray starts above the surface, along the normal.  A computed hit point lies
# a rounding error (about 1e-15 here) off its surface, often just inside: a ray started there
# would hit its own surface.  Any offset between 1e-9 and 1e-4 gives the same answers.
OFFSET = 1e-6


def in_shadow(point, normal, light, spheres):
    """Whether the point light at L is hidden from the surface point p.

    Inputs: point p on a surface (it may lie a rounding error inside it), the surface's unit
    normal n there (pointing out of the surface), the light's position L (3 numbers each), and
    spheres, a list of (center, radius) pairs: the occluders, p's own sphere among them.
    Output: True when p is in shadow, False when the light reaches it.

    The shadow ray starts a little above the surface, s = p + ε n, and runs to the light:
        x(λ) = s + λ (L − s),   0 < λ < 1
    p is in shadow when some sphere meets that segment (a root λ of the ray-sphere quadratic
    with 0 < λ < 1: before the light, not behind the start).  A point whose surface faces away
    from the light (n·(L − p) < 0) is in shadow of its own sphere: the ray passes through it.

    >>> in_shadow((0, 1, 0), (0, 1, 0), (0, 5, 0), [((0, 0, 0), 1.0), ((0, 3, 0), 0.5)])
    True
    """
    p, n, L = (np.asarray(v, float) for v in (point, normal, light))
    start = p + OFFSET * n
    r = L - start
    a = float(r @ r)
    for center, radius in spheres:
        oc = start - np.asarray(center, float)
        b = 2.0 * float(r @ oc)
        c = float(oc @ oc) - radius * radius
        disc = b * b - 4.0 * a * c
        if disc < 0.0:
            continue
        root = math.sqrt(disc)
        for lam in ((-b - root) / (2.0 * a), (-b + root) / (2.0 * a)):
            if 0.0 < lam < 1.0:
                return True
    return False
