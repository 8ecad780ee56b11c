"""The windings of a rect or disk light's crowded pixels, a block of pixels at a time
(`raytrace.exact_soft`; numba only: `raytrace.blockkernels`).

The pixels are taken in blocks of the image (`exact_soft.block_side` a side).  A block's steady
triangles (turned one way from each of its points, free from each) are counted once, edge by
edge, and only the edges left of them are carried from each pixel onto the light's plane; each
pixel adds its own pairs of the block's unsteady triangles (the candidate query, the cut and
the whole shadows of `raytrace.exact_soft`, as before), and its outline, cut to a box about
the light (`windings.clip_box`), is noded as `raytrace.windings` does.  A pixel is left to
the pixel-by-pixel path where its block meets a convex object's cluster (those are united as
hulls) or, in a chunk with such a block, no more than a few triangles (`chains`' crowded),
where more than `windings.LOOSE` of its own shadows are not free (a contact; up to that many
are taken away apart, as `windings.split` does), or where its windings are in doubt.
"""

from __future__ import annotations

import numpy as np

from . import pyramid, windings, windmeasures
from .candidates import COPLANAR_RELATIVE
from .lightshapes import FramedLight
from .occluders import RUN, Objects
from .polygons import dot, kernels

# Outline edges carried at once (whole blocks: their arrays stay in the caches).
CARRIED = 1 << 16
# The most holes an object may have for the one-way rule (`_one_way`): each is a cone to test.
HOLES = 64


def chains(light: FramedLight, objects: Objects, corners: np.ndarray, h: tuple,
           p: np.ndarray, own: np.ndarray, where: np.ndarray, width: int, block: int,
           crowded: int = 0, eye: float = np.inf
           ) -> tuple[np.ndarray, np.ndarray, tuple | None]:
    """(n,) object each: the boundary of each pixel's shadows' union inside the light's box
    (`windings.boundaries`), None where it is left to the pixel-by-pixel path (module) or
    the kernels are missing; and the few shadows that are not free at a contact, left out of
    it (`windings.split`'s loose: `windmeasures.measures` takes them away; None where none);
    and the clusters that meet some pyramid of each pixel's block (no other can meet its own:
    `candidates.meets`' among for the pixel-by-pixel path) as (the blocks' (b, C) bool, each
    pixel's block (n,)), None where no blocks were made; points p (n, 3) on triangles own
    (n,) at image pixels where (n,) of a frame `width` wide, in blocks of `block` a side; h:
    the cluster members' corners' heights (C, CLUSTER, 3) and each cluster's range of them
    (C, 2) (`candidates.heights`' third and fourth); crowded: a block that meets no more
    triangles is left out where some block is anyway (a convex object's: that path's
    fixed cost paid), else one that meets none (docs/speed.md); eye: how far from the eye
    (the frame's origin: inf where the eye is elsewhere) every primary ray starts (the near
    plane's farthest corner, `RayGrid.farthest_start`; the one-way rule, `_one_way`, holds
    no object nearer; inf: none)."""
    out, out_loose = np.full(len(p), None, object), np.full(len(p), None, object)
    loaded = kernels("blockkernels")
    member = objects.members >= 0
    plain = ((objects.kinds & 1) == 0) & member
    if loaded is None or kernels("windingkernels") is None or objects.cones is None or \
            len(p) == 0 or plain.sum() <= crowded:   # numba's (`Objects.holes`, `.cones`)
        return out, out_loose, None
    y, x = np.divmod(where, width)
    key = (y // block) * -(-width // block) + x // block
    order = np.argsort(key, kind="stable")
    p, own = p[order], own[order]
    start = np.r_[np.flatnonzero(np.r_[True, np.diff(key[order]) != 0]), len(p)]
    base = light.center + light.hull @ light.axes
    lo, hi = np.minimum(p, base.min(axis=0)), np.maximum(p, base.max(axis=0))
    # the clusters that meet some pixel's pyramid of each block (b, C); a block that meets a
    # convex object's is left to the pixels' own path (its hulls); so are a few (crowded)
    top = dot(p - light.center, light.normal)
    m = pyramid.sides(light, p, base)
    sides = np.stack([s / np.linalg.norm(s, axis=1, keepdims=True) for s in m])
    near, many, hull = loaded.block_meets(
        start, lo, hi, top, sides, p, objects.lo, objects.hi, objects.centre, objects.radius,
        (objects.centre - light.center) @ light.normal, member.sum(axis=1),
        (((objects.kinds & 1) != 0) & member).any(axis=1), RUN, objects.run_lo,
        objects.run_hi, objects.run_centre, objects.run_radius)
    block = np.repeat(np.arange(len(start) - 1), np.diff(start))
    met = (near.copy(), np.empty(len(p), np.int64))
    met[1][order] = block
    hull |= many <= (crowded if hull.any() else 0)
    if hull.all():
        return out, out_loose, met
    near[hull] = False
    ways = (objects.owner, _one_way(objects, base, eye), *objects.holes[:3], objects.centre,
            objects.radius, objects.cones, h[1])
    e_tri, e_from, e_to, e_cnt, e_at, unsteady, to_cut, u_at, convex, u_way = \
        loaded.block_edges(
            start, near, objects.members, objects.packed, objects.kinds, objects.member_ids, h[0],
            p, top, own, objects.normal, objects.offset, objects.scale, corners,
            np.sqrt(dot(p - light.center, p - light.center)),
            pyramid.UNCUT_REACH * np.abs(light.hull).max(), COPLANAR_RELATIVE, sides,
            int(many[~hull].max()), ways)
    flat, free, pix, tri, count, whole = _own_pairs(light, objects, corners, p, own, lo, hi,
                                                    base, (m, sides), block, unsteady, to_cut,
                                                    u_at, u_way)
    ok = ~(convex | hull)[block]
    # a few shadows that are not free (`windings.split`): cut, carried, turned, apart
    ok &= np.bincount(pix[~free], minlength=len(p)) <= windings.LOOSE
    apart = np.flatnonzero(~free & ok[pix])
    turned, sure = windmeasures.turned(
        pyramid.carry(light, p, pyramid.pieces(light, corners, p, pix[apart], tri[apart], m,
                                               max(3, int(count[apart].max(initial=3)))),
                      pix[apart], whole[apart]), count[apart])
    ok[pix[apart[~sure]]] = False
    got = _wound(loaded, light, objects, corners, p, start, (e_tri, e_from, e_to, e_cnt, e_at),
                 flat[free], pix[free], tri[free])
    got[~ok] = None
    settled = np.flatnonzero(windings.found(got)[pix[apart]])
    loose = np.full(len(p), None, object)
    for k, group in zip(*windings.groups(pix[apart[settled]], settled)):
        loose[k] = (turned[group], count[apart[group]])
    out[order], out_loose[order] = got, loose
    return out, out_loose, met


def _wound(loaded, light: FramedLight, objects: Objects, corners: np.ndarray, p: np.ndarray,
           start: np.ndarray, edges: tuple, flat: np.ndarray, pix: np.ndarray, tri: np.ndarray
           ) -> np.ndarray:
    """(n,) object: `windings.boundaries` of each pixel's free shadows flat (q, 3, 2) of
    triangles tri (q,) (pix (q,) ascending) and its block's (start (b + 1,)) outline edges
    (`blockkernels.block_edges`' five), carried from it, cut to the light's box; whole blocks
    at a time, about CARRIED carried edges each."""
    e_tri, e_from, e_to, e_cnt, e_at = edges
    got = np.full(len(p), None, object)
    box = windings.clip_box(light)
    size = np.diff(start) * np.diff(e_at)
    cut = np.flatnonzero(np.r_[True, np.diff(np.cumsum(size) // CARRIED) != 0])
    for b0, b1 in zip(cut.tolist(), np.r_[cut[1:], len(start) - 1].tolist()):
        i0, i1 = start[b0], start[b1]
        rims = loaded.carried_edges(start[b0:b1 + 1] - i0, e_tri, e_from, e_to, e_cnt,
                                    e_at[b0:b1 + 1], corners, objects.corner_ids, p[i0:i1],
                                    light.center, light.normal, light.axes, box)
        a, b = np.searchsorted(pix, [i0, i1])
        got[i0:i1] = windings.boundaries(flat[a:b], np.ones(b - a, bool),
                                         objects.corner_ids[tri[a:b]], pix[a:b] - i0, i1 - i0,
                                         rims=rims, box=box, partial=True)
    return got


def _own_pairs(light: FramedLight, objects: Objects, corners: np.ndarray, p: np.ndarray,
               own: np.ndarray, lo: np.ndarray, hi: np.ndarray, base: np.ndarray,
               sides: tuple, block: np.ndarray, unsteady: np.ndarray, to_cut: np.ndarray,
               u_at: np.ndarray, u_way: np.ndarray) -> tuple[np.ndarray, ...]:
    """Each pixel's pairs of its block's unsteady triangles (block (n,), unsteady (u,) from
    u_at (b + 1,)) with their whole shadows: (flat (q, 3, 2), free (q,), pixel (q,)
    ascending, triangle (q,), and the cut's count and whole (q,) (3 and True for the
    uncut)): of those free from every pixel of the block, those not wholly outside a side
    plane of the pixel's pyramid, and of the others (to_cut (u,)) those `candidates.pairs`
    would keep and the pyramid's cut keeps; sides: the pyramids' side planes (`pyramid.
    sides`' list, and those normals made unit (s, n, 3))."""
    m, unit = sides
    *uncut, pix, tri = kernels("blockkernels").own_candidates(
        block, unsteady, to_cut, u_at, own, objects.tri_lo, objects.tri_hi, lo, hi,
        objects.normal, objects.offset, objects.scale, corners, COPLANAR_RELATIVE, p, u_way,
        unit)
    _, count, pix, tri, whole = pyramid.cut(light, corners, p, pix, tri, base, m, store=False)
    pix, tri = np.r_[uncut[0], pix], np.r_[uncut[1], tri]
    count = np.r_[np.full(len(uncut[0]), 3), count]
    whole = np.r_[np.ones(len(uncut[0]), bool), whole]
    order = np.argsort(pix, kind="stable")
    pix, tri, count, whole = pix[order], tri[order], count[order], whole[order]
    flat, free = pyramid.uncut(light, corners, p, pix, tri)
    return flat, free, pix, tri, count, whole


def _one_way(objects: Objects, base: np.ndarray, eye: float) -> np.ndarray:
    """(n_objects,) bool: the objects the block path may count one way (`raytrace.onewaykernels`):
    those with `occluders.Objects.holes`, no more than HOLES of them, whose box lies farther
    from the eye (the frame's origin) than `eye` and apart from the box of the light's corners
    base (k, 3), by 2^-20 of the coordinates for the roundings (no point of the light, and
    no primary ray's start, then lies within the object and its holes' caps)."""
    if not np.isfinite(eye):
        return np.zeros(len(objects.bodies), bool)
    hole_at, _, _, lo, hi = objects.holes
    size = np.maximum(np.abs(lo), np.abs(hi)).max(axis=1, initial=0.0)
    pad = 2.0 ** -20 * (size + np.abs(base).max())
    gap = np.sqrt((np.maximum(np.maximum(lo, -hi), 0.0) ** 2).sum(axis=1))
    apart = (base.min(axis=0) > hi + pad[:, None]).any(axis=1) | \
        (base.max(axis=0) < lo - pad[:, None]).any(axis=1)
    return np.isfinite(size) & (np.diff(hole_at) <= HOLES) & \
        (gap > eye * (1 + 2.0 ** -20) + pad) & apart
