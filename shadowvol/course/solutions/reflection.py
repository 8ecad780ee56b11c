"""Task: the ideal (mirror) reflection of a direction."""

import numpy as np


def reflect(direction, normal):
    """The mirror reflection of the direction d about a surface with normal n.

    Inputs: direction d (any length) and normal n (any length, not zero), sequences of 2 or 3
    numbers.  n may point to either side of the surface.
    Output: the reflected direction as a sequence of numbers, as long as d.

    With the unit normal n̂ = n / |n|:   r = d − 2 (n̂·d) n̂
    (the component of d along the normal turns round, the rest stays).

    >>> [float(x) for x in reflect((1, -1, 0), (0, 2, 0))]
    [1.0, 1.0, 0.0]
    """
    d, n = np.asarray(direction, float), np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    return d - 2.0 * float(n @ d) * n
