"""Whether a block's points see a triangle turned one way (`raytrace.blockkernels`).

`block_edges` counts a triangle once for a block where every point p of it sees the triangle
turned the same way, certainly (p off its plane by more than FACING of their distance), free
from each and carried within reach (`_steady`).  Most triangles it meets are so by a wide
margin, and one point tells it (`_facing`): a triangle whose plane lies farther from the
block's first point p_0 than the ball about p_0 that holds the others (more FACING of the
farthest distance, and 2^-36 of it for the roundings) is turned the same way from each, and
within reach of each where it is within reach of the ball's farthest point.  Only the others
are tested point by point.  Whether it is some pixel's own, or coplanar with one, is asked
once for each distinct own triangle of the block (`_distinct`, `_mine`): a block on a floor
has one or two.  The same classes as point by point, so the same outline and bytes
(`block_edges` 0.76x on the bunny 256 x 256's, 0.89x on its 128 x 128's).

A cluster turned away from every point (its sphere, normal cone and heights: `_ahead`,
`_behind`) is passed over whole.  Each is inlined and handed floats where it can: numba
counts references to an array an inlined function reads under a branch (docs/speed.md,
"Reference counts"); asked point by point within `_steady`, the ball's test made it count
seven arrays' references for every member, and `block_edges` took 1.2-1.4x.
"""

from __future__ import annotations

import numpy as np

from .exactkernels import FACING, coplanar_with
from .packetkernels import _jit

# `_facing`'s margin over FACING for the roundings (the points' own tests are good to
# ~2^-49 of their distances), and its reach's (theirs 1 + 2^-30).
_SLACK = FACING + 2.0 ** -36
_WIDER = 1 + 2.0 ** -29


@_jit(inline="always")
def _tops(i0, i1, top, rel, p):
    """The lowest and highest of the block's pixels' heights top i0..i1, the farthest of
    their distances rel from the light's centre, and `_facing`'s ball: the radius about
    the first point p_i0 (p (n, 3)) that holds the others (2^-40 more for the roundings),
    and p_i0."""
    low_top, high_top, far_rel, ball = np.inf, 0.0, 0.0, 0.0
    for i in range(i0, i1):
        low_top, high_top = min(low_top, top[i]), max(high_top, top[i])
        far_rel = max(far_rel, rel[i])
        d0, d1, d2 = p[i, 0] - p[i0, 0], p[i, 1] - p[i0, 1], p[i, 2] - p[i0, 2]
        ball = max(ball, np.sqrt(d0 * d0 + d1 * d1 + d2 * d2))
    return low_top, high_top, far_rel, (ball * (1 + 2.0 ** -40), p[i0, 0], p[i0, 1], p[i0, 2])


@_jit(inline="always")
def _distinct(i0, i1, own, owns):
    """The distinct triangles of own[i0:i1] written into owns, in order: how many."""
    n = 0
    for i in range(i0, i1):
        seen = False
        for g in range(n):
            seen |= owns[g] == own[i]
        if not seen:
            owns[n] = own[i]
            n += 1
    return n


@_jit(inline="always")
def _member(c, k, packed, h):
    """Member k of cluster c's lowest and highest corner heights over the light's plane and
    its box's diagonal (the span `_facing` and `_steady` bound its reach by)."""
    low_h = min(h[c, k, 0], min(h[c, k, 1], h[c, k, 2]))
    high_h = max(h[c, k, 0], max(h[c, k, 1], h[c, k, 2]))
    span = 0.0
    for a in range(3):
        span += (packed[c, k, 3 + a] - packed[c, k, a]) ** 2
    return low_h, high_h, np.sqrt(span)


@_jit(inline="always")
def _facing(c, k, packed, h, ball, low_top, high_top, far_rel, reach):
    """+1 or -1: what `_steady` gives member k of cluster c where it is no pixel's own nor
    coplanar with one, from the block's first point p_0 alone; else 0 (`_steady` decides);
    and the member's `_member` (made once, for `_steady` too).  ball (`_tops`'): the
    radius R about p_0 that holds the block's points, and p_0.  With d = |p_0 - corner| and
    s its distance off the member's plane, every point's own s lies within R of s and its
    distance within d + R, so |s| > R + (FACING + 2^-36) (d + R) turns the member the same
    way from each by more than FACING of its distance (2^-36 covers each test's roundings,
    ~2^-49 of it), and the reach bound at d + R, 1 + 2^-29 over it, holds each point's (1
    + 2^-30 over its own, `_steady`'s).  The same heights' tests as `_steady`'s first, the
    same span and grow."""
    shape = _member(c, k, packed, h)
    low_h, high_h, span = shape
    if not (low_h >= 0 and high_h < low_top and low_h < high_top):
        return 0, shape
    m0, m1, m2 = packed[c, k, 6], packed[c, k, 7], packed[c, k, 8]
    r0, r1, r2 = ball[1] - packed[c, k, 12], ball[2] - packed[c, k, 13], \
        ball[3] - packed[c, k, 14]
    grow = high_top / (low_top - high_h)
    dist = np.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
    s = m0 * r0 + m1 * r1 + m2 * r2
    if abs(s) > ball[0] + _SLACK * (dist + ball[0]) and \
            (far_rel + grow * (dist + ball[0] + span)) * _WIDER < reach:
        return 1 if s > 0 else -1, shape
    return 0, shape


@_jit(inline="always")
def _mine(t, c, k, packed, owns, n_own, corners, tri_normal, offset, scale, coplanar):
    """Whether triangle t (member k of cluster c) is one of owns[:n_own] or coplanar with
    one."""
    m0, m1, m2, scale_t = packed[c, k, 6], packed[c, k, 7], packed[c, k, 8], packed[c, k, 15]
    for g in range(n_own):
        o = owns[g]
        if t == o or coplanar_with(corners, t, o, m0, m1, m2, tri_normal, offset, scale_t,
                                   scale[o], coplanar):
            return True
    return False


@_jit(inline="always")
def _steady(c, k, i0, i1, packed, shape, p, low_top, high_top, far_rel, reach, mine):
    """+1 or -1: member k of cluster c (shape: `_member`'s) is free from every pixel i0..i1 and
    turned that way from each, certainly; 2: free from each, not turned one way; 3: in no
    pixel's pyramid (wholly at or beyond every p's parallel plane, or behind the light's); 0
    for any other (mine: some pixel's own, or coplanar with it; or free from some only)."""
    low_h, high_h, span = shape
    if low_h >= high_top or high_h < 0:
        return 3
    if mine or not (low_h >= 0 and high_h < low_top):
        return 0
    # carried within reach: |rel| + the most any corner is magnified times its distance
    # (within the triangle's box's diagonal, span, of its first corner); the root and the
    # quotient once a triangle, not a pixel (numba leaves a root in the loop: 6 % of it)
    grow = high_top / (low_top - high_h)
    sign, turned = 0, True
    for i in range(i0, i1):
        r0, r1, r2 = p[i, 0] - packed[c, k, 12], p[i, 1] - packed[c, k, 13], \
            p[i, 2] - packed[c, k, 14]
        dist = np.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
        s = packed[c, k, 6] * r0 + packed[c, k, 7] * r1 + packed[c, k, 8] * r2
        way = 1 if s > 0 else -1
        if not abs(s) > FACING * dist or (sign != 0 and way != sign):
            turned = False
        sign = way
        bound = far_rel + grow * (dist + span)
        if not bound * (1 + 2.0 ** -30) < reach:
            return 0
    return sign if turned else 2


@_jit(inline="always")
def _ahead(cos, low_h, high_h, low_top, high_top):
    """`_behind`'s grow for a cluster whose normal cone is narrower than a half space (cos t >
    0) and whose members' heights low_h..high_h lie between the light's plane and the block's
    lowest parallel plane (low_top; high_top its highest): high_top / (low_top - high_h),
    else -1 (the cluster is not passed whole)."""
    if cos > 0 and low_h >= 0 and high_h < low_top:
        return high_top / (low_top - high_h)
    return -1.0


@_jit(inline="always")
def _behind(d0, d1, d2, a0, a1, a2, cos, sin, r, grow, far_rel, reach):
    """Whether `_steady` would give every member of a cluster -1 as seen from p (turned away
    by more than FACING of its distance, free, carried within reach), d = p - centre (the
    cluster's sphere: centre, radius r; its normal cone (`occluderkernels.cones`): axis a,
    half angle t, cos t, sin t; grow: the block's highest height over its lowest less the
    top of the cluster's heights): every member's normal n within t of a, and its corners
    within r of the centre, n . (p - corner) <= |d| cos(f - t) + r for d at the angle f
    from a; that less than -FACING (|d| + r), the corner's distance at most; and each
    member's reach bound at most the cluster's (its height at most the heights' top, its
    distance at most |d| + r, its box's diagonal 2 r).  A margin of 2^-30 of the terms
    covers the roundings, the members' and these.  The caller tests the cone and the
    heights first (`_ahead`) and hands floats, not arrays (the module docstring)."""
    size = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    along = a0 * d0 + a1 * d1 + a2 * d2
    x0, x1, x2 = a1 * d2 - a2 * d1, a2 * d0 - a0 * d2, a0 * d1 - a1 * d0
    across = np.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
    most = along * cos + across * sin + r + FACING * (size + r)
    return most + 2.0 ** -30 * (abs(along) + size + r) < 0 and \
        (far_rel + grow * (size + 3 * r)) * (1 + 2.0 ** -20) < reach
