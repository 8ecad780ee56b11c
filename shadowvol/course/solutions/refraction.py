"""Task: refraction by Snell's law, with total internal reflection."""

import math

import numpy as np


def refract(direction, normal, n1, n2):
    """The refracted direction of a ray crossing from a medium of index n1 into one of n2.

    Inputs: direction d (unit length), normal n (unit length, on the side the ray comes from:
    n·d < 0), the refractive indices n1 (where the ray comes from) and n2 (where it goes).
    Output: (t, tir): t the outgoing unit direction as a sequence of numbers, and tir a bool,
    True for total internal reflection, when t is the mirror reflection d − 2 (n·d) n.

    Snell: n1 sin θ1 = n2 sin θ2.  With η = n1 / n2 and cos θ1 = −n·d:
        k = 1 − η² (1 − cos² θ1)          (= cos² θ2)
        k < 0:  sin θ2 would exceed 1: total internal reflection
        else:   t = η d + (η cos θ1 − √k) n
    Exactly at the critical angle (k = 0) t grazes the surface; rounding decides the sign of
    k there, and either answer is right as long as t goes with tir.

    >>> t, tir = refract((0, -1, 0), (0, 1, 0), 1.0, 1.5)   # head-on: straight through
    >>> [float(x) for x in t], tir
    ([0.0, -1.0, 0.0], False)
    """
    d, n = np.asarray(direction, float), np.asarray(normal, float)
    eta = n1 / n2
    cos1 = -float(n @ d)
    k = 1.0 - eta * eta * (1.0 - cos1 * cos1)
    if k < 0.0:
        return d - 2.0 * float(n @ d) * n, True
    return eta * d + (eta * cos1 - math.sqrt(k)) * n, False
