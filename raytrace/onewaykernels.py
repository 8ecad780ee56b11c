"""The block path's one-way rule, in numba (`raytrace.blockkernels`, numba only as it is).

The block path counts a triangle's shadow with winding +1 whichever way it turns (a triangle
turned away from p is pushed the other way round), so the covered part of the light is
where the winding is not 0, and a closed object counts each of its layers.  Half of them
would do.  Close an object M with caps C over its holes: a fan from a point in each ball
of `occluderkernels.holes` over that hole's edges, so that M + C is a closed surface (its
edges cancel) and has a winding number w about every point off it, changing by +1 where a
segment crosses a triangle turned toward the segment's start (`toward`) and by -1 where it
crosses one turned away.  If w is 0 at p and at every point x of the light, a segment from
p to x that crosses M crosses a triangle turned toward p, or it crosses a cap: the changes
add up to 0.  So p sees x past M exactly where it sees it past M's triangles turned toward
p and those turned away that a segment through a cap may meet: the triangles turned away
from every point of a block, outside the cone from the block through each hole's ball,
can be left out (their shadows lie within those of the others), and so can an unsteady
triangle turned away from the pixel at hand.  Fewer edges are left after the tally (the
back layers' rims go), fewer are carried, and fewer cross in the winding kernel: the same
measures, up to rounding (tests/raytrace/test_block_windings.py).

When w is 0: at the light's points, where the light's corners' box lies apart from M's box
(M + C lies within it); at p, where the segment from the eye reaches p crossing none of M
(p is visible) nor a cap (`clear`: it passes outside the holes' balls) and the eye lies
outside M's box farther than a primary ray's start (`blockwindings._one_way`), unless p lies
on M itself other than on its own triangle (or one coplanar with it), where w about p is in
doubt (`through`: an edge of a fold through p, a contact): there the rule is off for the
block, and so for an object with more than `blockwindings.HOLES` holes.
"""

from __future__ import annotations

import numpy as np

from .exactkernels import coplanar_with
from .packetkernels import _jit


@_jit()
def settle(nt, later, most, u0, nu, u_c, u_way, b, i0, i1, p, own, way, cone, axes, ways,
           members, tris):
    """The end of block b's members (`blockkernels.block_edges`), once a block, before its
    members turned away are pushed (`blockkernels._turned_away`): of its members in doubt
    (later[:, most:most + nt]: cluster, member) one that may pass through a pixel's p takes
    its object off the one-way rule (`through`); its unsteady triangles u0..nu (clusters
    u_c) are marked in u_way where they may be left out of a pixel's pairs (their object on
    the rule, their cluster meeting no hole's cone: `kept`).  tris: packed, corners,
    tri_normal, offset, scale, coplanar, facing (`through`'s)."""
    owner = ways[0]
    packed, corners, tri_normal, offset, scale, coplanar, facing = tris
    for g in range(most, most + nt):
        c, k = later[0, g], later[1, g]
        if way[owner[c]] and through(members[c, k], c, k, i0, i1, packed, p, own, corners,
                                     tri_normal, offset, scale, coplanar, facing):
            way[owner[c]] = False
    for g in range(u0, nu):
        c = u_c[g]
        if way[owner[c]] and not (cone[c] >= 0 and cone[c] >> 1 == b):
            kept(c, b, i0, p, cone, ways, axes)
        u_way[g] = way[owner[c]] and cone[c] & 1 == 0


@_jit()
def clear(o, i0, i1, p, ways, axes):
    """Whether the segment from the eye (the frame's origin) to each pixel's p i0..i1 passes
    outside every hole's ball of object o (the module: no cap between them), with a margin
    of 2^-20 of the distances for the roundings; and axes (H, 6) of o's holes made for
    `kept`: from the block's first p, the unit axis to the hole's centre, the sine and
    cosine of the half angle of the cone tangent to its ball grown by the block's spread
    (the farthest of its pixels from the first; the sine 2 where p lies in that ball, -1
    where the caller finds the ball out of every pixel's pyramid), the spread."""
    at, centre, radius = ways[2], ways[3], ways[4]
    clear = True
    spread = 0.0
    for i in range(i0, i1):
        px, py, pz = p[i, 0], p[i, 1], p[i, 2]
        pp = px * px + py * py + pz * pz
        dx, dy, dz = px - p[i0, 0], py - p[i0, 1], pz - p[i0, 2]
        spread = max(spread, np.sqrt(dx * dx + dy * dy + dz * dz))
        for g in range(at[o], at[o + 1]):
            cx, cy, cz = centre[g, 0], centre[g, 1], centre[g, 2]
            s = min(max((cx * px + cy * py + cz * pz) / pp, 0.0), 1.0) if pp > 0 else 0.0
            dx, dy, dz = s * px - cx, s * py - cy, s * pz - cz
            gap = np.sqrt(dx * dx + dy * dy + dz * dz)
            margin = 2.0 ** -20 * (np.sqrt(pp) + abs(cx) + abs(cy) + abs(cz))
            clear &= gap > radius[g] * (1 + 2.0 ** -20) + margin
    spread *= 1 + 2.0 ** -20
    for g in range(at[o], at[o + 1]):
        wx, wy, wz = centre[g, 0] - p[i0, 0], centre[g, 1] - p[i0, 1], centre[g, 2] - p[i0, 2]
        far = np.sqrt(wx * wx + wy * wy + wz * wz)
        grown = radius[g] + spread
        axes[g, 5] = spread
        if not far > grown + 2.0 ** -20 * (far + grown + abs(p[i0, 0]) + abs(p[i0, 1])
                                           + abs(p[i0, 2])):
            axes[g, 3] = 2.0
            continue
        axes[g, 0], axes[g, 1], axes[g, 2] = wx / far, wy / far, wz / far
        axes[g, 3] = grown / far
        axes[g, 4] = np.sqrt(1 - axes[g, 3] * axes[g, 3])
    return clear


@_jit()
def kept(c, b, i0, p, cone, ways, axes):
    """Whether cluster c's sphere may meet the cone from some pixel's p of block b (i0 its
    first) tangent to a hole's ball of its object (all of space where p is in the ball):
    the module, its members turned away are kept.  Each of those cones lies within the
    block's spread of the cone from the first p tangent to the ball grown by the spread
    (axes: `clear`'s), so the sphere, grown by the spread, is tested against that one:
    kept where its centre's signed distance from the cone's side in the plane of p, the
    axis and the centre is within its radius (that distance is never more than the
    centre's distance from the cone: where the nearest point is p, it is less), a margin
    of 2^-20 of the distances for the roundings.  Once a block: cone (C,) holds 2 b + the
    answer."""
    at, c_centre, c_radius = ways[2], ways[5], ways[6]
    o = ways[0][c]
    kept = False
    vx, vy, vz = c_centre[c, 0] - p[i0, 0], c_centre[c, 1] - p[i0, 1], \
        c_centre[c, 2] - p[i0, 2]
    vv = vx * vx + vy * vy + vz * vz
    size = abs(vx) + abs(vy) + abs(vz) + abs(p[i0, 0]) + abs(p[i0, 1]) + abs(p[i0, 2])
    for g in range(at[o], at[o + 1]):
        if axes[g, 3] < 0.0:
            continue
        if axes[g, 3] > 1.0:
            kept = True
            break
        d = vx * axes[g, 0] + vy * axes[g, 1] + vz * axes[g, 2]
        reach = c_radius[c] + axes[g, 5]
        reach += 2.0 ** -20 * (reach + size)
        rhs = d * axes[g, 3] + reach
        if rhs >= 0 and (vv - d * d) * axes[g, 4] * axes[g, 4] <= rhs * rhs:
            kept = True
            break
    cone[c] = 2 * b + (1 if kept else 0)
    return kept


@_jit(inline="always")
def spot(i0, i1, p, spot):
    """spot (7,): the box of the block's points p i0..i1 (lo, hi) and their largest
    coordinate (`boxes_touch`)."""
    for a in range(3):
        spot[a], spot[3 + a] = p[i0, a], p[i0, a]
    for i in range(i0 + 1, i1):
        for a in range(3):
            spot[a], spot[3 + a] = min(spot[a], p[i, a]), max(spot[3 + a], p[i, a])
    spot[6] = max(max(abs(spot[0]), abs(spot[3])), max(max(abs(spot[1]), abs(spot[4])),
                                                       max(abs(spot[2]), abs(spot[5]))))


@_jit(inline="always")
def boxes_touch(c, k, packed, spot, facing):
    """Whether member k of cluster c's box, grown by `through`'s margin, meets the box of
    the block's points (spot: `spot`'s): `through`'s first test, for them all at once."""
    pad = facing * (3 * spot[6] + packed[c, k, 15])
    return (packed[c, k, 0] - pad <= spot[3]) & (packed[c, k, 3] + pad >= spot[0]) & \
        (packed[c, k, 1] - pad <= spot[4]) & (packed[c, k, 4] + pad >= spot[1]) & \
        (packed[c, k, 2] - pad <= spot[5]) & (packed[c, k, 5] + pad >= spot[2])


@_jit()
def through(t, c, k, i0, i1, packed, p, own, corners, tri_normal, offset, scale, coplanar,
            facing):
    """Whether triangle t (member k of cluster c) may pass through some pixel's p i0..i1
    other than its own's or one coplanar with it: p in its box (a margin of `facing` of the
    coordinates) and not off its plane by more than `facing` of their distance, as
    `facingkernels._steady` tells a triangle turned one way (the module: there the object's
    winding about p is in doubt)."""
    for i in range(i0, i1):
        pad = facing * (abs(p[i, 0]) + abs(p[i, 1]) + abs(p[i, 2]) + packed[c, k, 15])
        inside = True
        for a in range(3):
            inside &= packed[c, k, a] - pad <= p[i, a] <= packed[c, k, 3 + a] + pad
        r0, r1, r2 = p[i, 0] - packed[c, k, 12], p[i, 1] - packed[c, k, 13], \
            p[i, 2] - packed[c, k, 14]
        s = packed[c, k, 6] * r0 + packed[c, k, 7] * r1 + packed[c, k, 8] * r2
        if not inside or abs(s) > facing * np.sqrt(r0 * r0 + r1 * r1 + r2 * r2):
            continue
        o = own[i]
        if not (t == o or coplanar_with(corners, t, o, packed[c, k, 6], packed[c, k, 7],
                                        packed[c, k, 8], tri_normal, offset, packed[c, k, 15],
                                        scale[o], coplanar)):
            return True
    return False
