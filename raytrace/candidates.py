"""The exact visibility's conservative candidate query (`raytrace.exact_soft`): for each pixel's
point p, the scene's triangles that may cut the pyramid from p over an area light, never
fewer (no sampled rays): the clusters whose boxes meet the pyramid's box and whose bounding
spheres no plane of the pyramid leaves wholly outside (`meets`), then their triangles whose
own boxes meet it (`pairs`), less p's own triangle and those coplanar with it, and the faces a
closed object's shadow does not need.  In numba where it loads (`raytrace.exactkernels`: the
same pairs in the same order), else in numpy.
"""

from __future__ import annotations

import numpy as np

from .lightshapes import FramedLight
from .occluders import CLUSTER, RUN, Objects
from .polygons import dot, kernels
from .pyramid import sides as side_normals

# A triangle is coplanar with p's own when its three corners lie within this much of the
# largest corner coordinate (the frame's, from the eye) of the own triangle's plane: the
# corners are float64 world positions (each a few roundings of 2^-53 from its transform) less
# the eye (one more), so two triangles of one world plane lie ~1e-15 of their coordinates
# apart; 2^-40 (~1e-12) is a thousand times that, and no model places a real occluder so
# flat and so close.  Left in, such a triangle a rounding above p would cut the whole pyramid.
COPLANAR_RELATIVE = 2.0 ** -40


def pairs(objects: Objects, corners: np.ndarray, p: np.ndarray, normal: np.ndarray,
          own: np.ndarray, meet: np.ndarray, lo: np.ndarray, hi: np.ndarray,
          clear: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(pixel, triangle) pairs (q,) int64 each: the triangles of the clusters that `meet`
    (n, C) says meet p's pyramid box [lo, hi] (n, 3) (`meets`), whose own boxes meet it
    too, less p's own triangle, those coplanar with it, a convex object's from its own
    outside, and the triangles of a closed non-convex object that do not turn their back to p
    where the light is outside that object (`clear` (n_objects,) bool): a segment from p to a
    point of the light outside a closed surface that meets it leaves it last through a face
    turned away from p, so those faces' shadows alone make the object's (up to segments
    grazing an edge: no area).  In numba where it loads (`exactkernels.pairs`), else `_keep`
    after the box pairs."""
    loaded = kernels()
    if loaded is not None:
        outside = dot(objects.outward[own], normal) > 0
        return loaded.pairs(meet, objects.members, objects.packed, objects.kinds, lo, hi, own,
                             objects.normal, objects.offset, objects.scale, objects.object,
                             outside, np.zeros(0, bool) if clear is None else clear, corners,
                             p, COPLANAR_RELATIVE)
    pix, tri = _box_pairs(objects, own, meet, lo, hi)
    keep = _keep(objects, corners, p, normal, own, pix, tri, clear)
    return pix[keep], tri[keep]


def _keep(objects: Objects, corners: np.ndarray, p: np.ndarray, normal: np.ndarray,
          own: np.ndarray, pix: np.ndarray, tri: np.ndarray, clear: np.ndarray | None
          ) -> np.ndarray:
    """(q,) bool: the pairs `pairs` keeps of the box pairs pix, tri (q,)."""
    # coplanar: every corner within COPLANAR_RELATIVE of p's own triangle's plane.  Only near-
    # parallel triangles are looked at: one tilted by more than 0.045 rad with its corners that
    # close to the plane is smaller than 2^-40 / 0.045 of its coordinates.
    own_n = objects.normal[own[pix]]
    parallel = np.flatnonzero(np.abs(dot(own_n, objects.normal[tri])) > 1 - 1e-3)
    keep = np.ones(len(tri), bool)
    if len(parallel):
        near, t = own[pix[parallel]], tri[parallel]
        off = np.abs(dot(corners[t], objects.normal[near][:, None])
                     - objects.offset[near, None])
        scale = np.maximum(objects.scale[near], objects.scale[t])
        keep[parallel] = off.max(axis=1) > COPLANAR_RELATIVE * scale
    mine = objects.convex[tri] & (objects.object[tri] == objects.object[own[pix]])
    outside = dot(objects.outward[own[pix]], normal[pix]) > 0
    keep &= ~(mine & outside)
    if clear is not None:
        shell = objects.shell[tri]
        closed = (shell != 0).any(axis=1) & ~objects.convex[tri] & clear[objects.object[tri]]
        at = np.flatnonzero(closed & keep)
        toward = dot(shell[at], corners[tri[at], 0] - p[pix[at]]) <= 0
        keep[at[toward]] = False
    return keep


def meets(light: FramedLight, objects: Objects, p: np.ndarray, base: np.ndarray,
          lo: np.ndarray, hi: np.ndarray, among: np.ndarray | None = None) -> np.ndarray:
    """(n, C) bool: cluster c's box meets the box lo, hi (n, 3) of the pyramid from p (n, 3)
    over `base` (k, 3), and its bounding sphere is not wholly outside one of the planes that
    bound the pyramid: its side planes through p, the light's plane and p's parallel plane
    (a sphere beyond a face of a convex body cannot meet it); among (n, C) bool: only those
    clusters (the others known not to meet: `blockwindings.chains`' blocks), None: all."""
    height = (objects.centre - light.center) @ light.normal              # (C,)
    top = (p - light.center) @ light.normal                               # (n,)
    sides = [m / np.linalg.norm(m, axis=1, keepdims=True) for m in side_normals(light, p, base)]
    loaded = kernels()
    if loaded is not None:
        return loaded.meets(lo, hi, objects.lo, objects.hi, objects.centre, objects.radius,
                             height, top, np.stack(sides), p,
                             np.zeros((0, 0), bool) if among is None else among, RUN,
                             objects.run_lo, objects.run_hi, objects.run_centre,
                             objects.run_radius)
    ok = np.ones((len(p), len(objects.lo)), bool)      # (n, C): axis by axis, no (n, C, 3)
    for a in range(3):
        ok &= objects.lo[None, :, a] <= hi[:, None, a]
        ok &= objects.hi[None, :, a] >= lo[:, None, a]
    ok &= (height >= -objects.radius)[None] & \
        (height[None] <= top[:, None] + objects.radius[None])
    for m in sides:
        ok &= dot(m[:, None], objects.centre[None]) - dot(m, p)[:, None] >= \
            -objects.radius[None]
    return ok if among is None else ok & among


def _box_pairs(objects: Objects, own: np.ndarray, meet: np.ndarray, lo: np.ndarray,
               hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`exactkernels.pairs` in numpy."""
    pix, clu = np.nonzero(meet)
    pix = np.repeat(pix, CLUSTER)
    tri = objects.members[clu].reshape(-1)
    keep = tri >= 0
    pix, tri = pix[keep], tri[keep]
    keep = np.ones(len(tri), bool)
    for a in range(3):
        keep &= objects.tri_lo[tri, a] <= hi[pix, a]
        keep &= objects.tri_hi[tri, a] >= lo[pix, a]
    keep &= tri != own[pix]
    return pix[keep], tri[keep]


def heights(light: FramedLight, objects: Objects, corners: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The corners' heights over the light's plane (M, 3) (the sums of `pyramid.uncut`, so its
    verdicts), (n_objects,) bool: the objects wholly on its emitting side (every corner
    strictly above: the light is outside them), the heights by cluster member (C,
    CLUSTER, 3) in the members' order (`Objects.packed`'s; pads: triangle 0's), and the
    least and most of those of each cluster (C, 2) (its pads' too: a range that holds its
    members')."""
    c, n = light.center, light.normal
    h = (corners[..., 0] - c[0]) * n[0] + (corners[..., 1] - c[1]) * n[1] + \
        (corners[..., 2] - c[2]) * n[2]
    lowest = np.full(int(objects.object.max(initial=-1)) + 1, np.inf)
    least = np.minimum(np.minimum(h[:, 0], h[:, 1]), h[:, 2])
    ids = objects.object
    if len(ids) and (ids[1:] >= ids[:-1]).all():      # objects side by side: one reduction
        first = np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]])
        lowest[ids[first]] = np.minimum.reduceat(least, first)
    else:
        np.minimum.at(lowest, ids, least)
    by_member = h[np.maximum(objects.members, 0)]
    flat = by_member.reshape(len(by_member), -1) if len(by_member) else np.zeros((0, 1))
    return h, lowest > 0, by_member, np.stack([flat.min(axis=1, initial=np.inf),
                                               flat.max(axis=1, initial=-np.inf)], axis=1)
