"""Task: counting along one eye ray, z-pass and z-fail, in a 2D cut through the scene."""

import numpy as np


def counts(light, polygon, eye, point):
    """The z-pass and z-fail counts of the eye ray to a surface point, for the shadow volume of
    one convex occluder (the textbook's silhouette volume), in 2D.

    Inputs: light L, eye E and the surface point P: (x, y) pairs; polygon, the occluder: a
    convex polygon as a list of (x, y) vertices, counter-clockwise, with L outside it.
    Output: (zpass, zfail), two ints.

    The volume is bounded by the near caps, the polygon's edges that face the light (their
    outward normal n has n·(L − a) > 0 for the edge's start a); two sides, one from each
    silhouette vertex S (a vertex between an edge facing the light and one facing away),
    the ray S + u (S − L), u >= 0, with the outward normal perpendicular to S − L pointing away
    from the other silhouette vertex; and the far cap at infinity, between the two sides.
    The eye ray is x(t) = E + t d with d = P − E, t > 0, so P is at t = 1.  A crossing is
    entering (+1) when d·n < 0 and leaving (−1) when d·n > 0, n the face's outward normal.
    When d points strictly between the two sides' directions S − L, the ray leaves through the
    far cap at t = ∞.
        zpass = the sum of the steps with t < 1        (from the eye to P)
        zfail = −(the sum of the steps with t > 1)     (from infinity back to P)
    P is in shadow when zfail > 0; zpass agrees with zfail unless the eye is inside the volume.

    >>> counts((0, 6), [(0, 3), (1, 3), (1, 4), (0, 4)], (-4, 2), (1, 0))
    (1, 1)
    """
    L, E, P = (np.asarray(v, float) for v in (light, eye, point))
    poly = [np.asarray(v, float) for v in polygon]
    k = len(poly)
    d = P - E
    faces = []   # (start, direction, outward normal, is a ray)
    facing = []
    for i in range(k):
        a, b = poly[i], poly[(i + 1) % k]
        n = np.array([b[1] - a[1], a[0] - b[0]])      # right of a -> b: outward for CCW
        facing.append(float(n @ (L - a)) > 0)
        if facing[-1]:
            faces.append((a, b - a, n, False))
    silhouette = [poly[i] for i in range(k) if facing[i - 1] != facing[i]]
    s1, s2 = silhouette
    for s, other in ((s1, s2), (s2, s1)):
        u = s - L
        n = np.array([-u[1], u[0]])
        if float(n @ (s - other)) < 0:
            n = -n
        faces.append((s, u, n, True))
    steps = []
    for a, f, n, ray in faces:
        den = d[0] * f[1] - d[1] * f[0]
        if den == 0.0:
            continue
        w = a - E
        t = (w[0] * f[1] - w[1] * f[0]) / den
        s = (w[0] * d[1] - w[1] * d[0]) / den
        if t > 0 and s >= 0 and (ray or s <= 1):
            steps.append((t, 1 if float(d @ n) < 0 else -1))
    u, v = s1 - L, s2 - L
    uv = u[0] * v[1] - u[1] * v[0]
    if (u[0] * d[1] - u[1] * d[0]) * uv > 0 and (d[0] * v[1] - d[1] * v[0]) * uv > 0:
        steps.append((np.inf, -1))
    zpass = sum(step for t, step in steps if t < 1)
    zfail = -sum(step for t, step in steps if t > 1)
    return zpass, zfail
