"""Task: the 2D exercise, the shadow of a segment lit by a point light in the unit square."""

import numpy as np

# Distance from L to the segment's line at or below which L counts as lying on it.
ON_LINE = 1e-9
# The square's corners, counter-clockwise from (0, 0); corner k sits at perimeter position k.
CORNERS = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]


def shadow_region(light, a, b):
    """The shadow that the segment a–b casts, lit by a point light L, inside the unit square.

    Inputs: the light L and the end points a, b: pairs (x, y) in the square [0, 1] x [0, 1].
    The segment is a two-sided occluder: it casts whichever side faces L.
    Output: the shadow region, a convex polygon as a list of (x, y) vertices, counter-clockwise
    (CCW), starting anywhere; [] when L lies on the segment's line (the shadow has no area).

    The region is bounded by the shadow polygons: the segment itself, and the rays from L
    through its end points, each from the end point on to where it leaves the square; and by
    the square's border between the two rays, with every corner of the square that it wraps
    around.  Name the end points p, q so that L lies to the right of p -> q; with p', q' where
    the rays through p and q leave the square, the region is
        p, q, q', (the square's corners passed walking CCW from q' to p'), p'
    A ray through an end point on the border has length zero: that vertex appears once.

    >>> shadow_region((0.5, 0.5), (0.6, 0.4), (0.6, 0.6))   # the wedge wraps round (1, 1)
    [(0.6, 0.6), (0.6, 0.4), (1.0, 0.0), (1.0, 1.0)]
    """
    L, a, b = (np.asarray(v, float) for v in (light, a, b))
    d = b - a
    side = (d[1] * (L[0] - a[0]) - d[0] * (L[1] - a[1])) / np.linalg.norm(d)
    if abs(side) <= ON_LINE:
        return []
    p, q = (a, b) if side > 0 else (b, a)
    q_out, s_q = _leave(q, q - L)
    p_out, s_p = _leave(p, p - L)
    region = [p, q, q_out]
    arc = (s_p - s_q) % 4.0
    for k in sorted(range(4), key=lambda k: (k - s_q) % 4.0):
        offset = (k - s_q) % 4.0
        if 1e-12 < offset < arc - 1e-12:
            region.append(np.asarray(CORNERS[k]))
    region.append(p_out)
    out = []
    for v in region:
        v = (float(v[0]), float(v[1]))
        if not out or v != out[-1]:
            out.append(v)
    if len(out) > 1 and out[0] == out[-1]:
        out.pop()
    return out


def _leave(origin, direction):
    """Where the ray origin + t·direction (t >= 0) leaves the square, and that point's position
    along the border: x on the bottom side, 1 + y on the right, 2 + (1 − x) on the top,
    3 + (1 − y) on the left (growing CCW)."""
    ts = []
    for axis in (0, 1):
        if direction[axis] > 0:
            ts.append(((1.0 - origin[axis]) / direction[axis], axis, 1.0))
        elif direction[axis] < 0:
            ts.append((-origin[axis] / direction[axis], axis, 0.0))
    t, axis, wall = min(ts)
    point = np.clip(origin + max(t, 0.0) * direction, 0.0, 1.0)
    point[axis] = wall
    x, y = point
    if axis == 1 and wall == 0.0:
        s = x
    elif axis == 0 and wall == 1.0:
        s = 1.0 + y
    elif axis == 1:
        s = 2.0 + (1.0 - x)
    else:
        s = 3.0 + (1.0 - y)
    return point, s % 4.0
