"""The windings of a rect or disk light's crowded pixels, a block of pixels at a time
(`raytrace.exact_soft`; numba only: `raytrace.blockkernels`).

The pixels are taken in blocks of the image (`exact_soft.BLOCK` a side).  A block's steady triangles
(turned one way from each of its points, free from each) are counted once, edge by edge,
and only the edges left of them are carried from each pixel onto the light's plane; each
pixel adds its own pairs of the block's unsteady triangles (the candidate query, the cut and
the whole shadows of `raytrace.exact_soft`, as before), and its outline, cut to a box about
the light (`windings.clip_box`), is noded as `raytrace.windings` does.  A pixel is left to
the pixel-by-pixel path where its block has a convex object's triangle (those are united as
hulls), where one of its own shadows is not free (a contact), or where its windings are in
doubt.
"""

from __future__ import annotations

import numpy as np

from . import pyramid, windings
from .candidates import COPLANAR_RELATIVE, _keep, meets
from .lightshapes import FramedLight
from .occluders import Objects
from .polygons import dot, kernels

# Outline edges carried at once (whole blocks: their arrays stay in the caches).
CARRIED = 1 << 16


def chains(light: FramedLight, objects: Objects, corners: np.ndarray, h: np.ndarray,
           p: np.ndarray, normal: np.ndarray, own: np.ndarray, where: np.ndarray, width: int,
           block: int) -> np.ndarray:
    """(n,) object: the boundary of each pixel's shadows' union inside the light's box
    (`windings.boundaries`), None where it is left to the pixel-by-pixel path (module) or
    the kernels are missing; points p (n, 3) with normals (n, 3) on triangles own (n,) at
    image pixels where (n,) of a frame `width` wide, in blocks of `block` a side; h (M, 3):
    the corners' heights (`candidates.heights`)."""
    out = np.full(len(p), None, object)
    loaded = kernels("blockkernels")
    if loaded is None or kernels("windingkernels") is None or len(p) == 0:
        return out
    y, x = np.divmod(where, width)
    key = (y // block) * -(-width // block) + x // block
    order = np.argsort(key, kind="stable")
    p, normal, own = p[order], normal[order], own[order]
    start = np.r_[np.flatnonzero(np.r_[True, np.diff(key[order]) != 0]), len(p)]
    base = light.center + light.hull @ light.axes
    lo, hi = np.minimum(p, base.min(axis=0)), np.maximum(p, base.max(axis=0))
    meet = meets(light, objects, p, base, lo, hi)
    top = dot(p - light.center, light.normal)
    rel = np.sqrt(dot(p - light.center, p - light.center))
    reach = pyramid.UNCUT_REACH * np.abs(light.hull).max()
    # the clusters that meet some pixel's pyramid of each block (b, C)
    near = loaded.any_rows(meet, start)
    sides = np.stack([m / np.linalg.norm(m, axis=1, keepdims=True)
                      for m in pyramid.sides(light, p, base)])
    e_tri, e_from, e_to, e_cnt, e_at, unsteady, loose, u_at, convex = loaded.block_edges(
        start, near, objects.members, objects.packed, objects.kinds, objects.corner_ids, h, p,
        top, own, objects.normal, objects.offset, objects.scale, corners, rel, reach,
        COPLANAR_RELATIVE, sides)
    block = np.repeat(np.arange(len(start) - 1), np.diff(start))
    flat, free, pix, tri = _own_pairs(light, objects, corners, p, normal, own, lo, hi, base,
                                      block, unsteady, loose, u_at)
    ok = np.ones(len(p), bool)
    ok[pix[~free]] = False
    ok[convex[block]] = False
    pix, tri, flat = pix[free], tri[free], flat[free]
    got = np.full(len(p), None, object)
    box = windings.clip_box(light)
    # whole blocks at a time, about CARRIED carried edges each
    size = np.diff(start) * np.diff(e_at)
    cut = np.flatnonzero(np.r_[True, np.diff(np.cumsum(size) // CARRIED) != 0])
    for b0, b1 in zip(cut.tolist(), np.r_[cut[1:], len(start) - 1].tolist()):
        i0, i1 = start[b0], start[b1]
        rims = loaded.carried_edges(start[b0:b1 + 1] - i0, e_tri, e_from, e_to, e_cnt,
                                    e_at[b0:b1 + 1], corners, objects.corner_ids, p[i0:i1],
                                    light.center, light.normal, light.axes)
        a, b = np.searchsorted(pix, [i0, i1])
        got[i0:i1] = windings.boundaries(flat[a:b], np.ones(b - a, bool),
                                         objects.corner_ids[tri[a:b]], pix[a:b] - i0, i1 - i0,
                                         rims=rims, box=box)
    got[~ok] = None
    out[order] = got
    return out


def _own_pairs(light: FramedLight, objects: Objects, corners: np.ndarray, p: np.ndarray,
               normal: np.ndarray, own: np.ndarray, lo: np.ndarray, hi: np.ndarray,
               base: np.ndarray, block: np.ndarray, unsteady: np.ndarray, loose: np.ndarray,
               u_at: np.ndarray) -> tuple[np.ndarray, ...]:
    """Each pixel's pairs of its block's unsteady triangles (block (n,), unsteady (u,) from
    u_at (b + 1,)) with their whole shadows: (flat (q, 3, 2), free (q,), pixel (q,)
    ascending, triangle (q,)): all of those free from every pixel of the block, and of the
    others (loose (u,)) those `candidates.pairs` would keep and the pyramid's cut keeps."""
    many = np.diff(u_at)[block]
    pix = np.repeat(np.arange(len(p)), many)
    first = np.repeat(u_at[block] - np.r_[0, np.cumsum(many)[:-1]], many)
    tri = unsteady[first + np.arange(len(pix))] if len(pix) else np.zeros(0, np.int64)
    free = ~loose[first + np.arange(len(pix))] if len(pix) else np.zeros(0, bool)
    pix, tri, whole = pix[~free], tri[~free], (pix[free], tri[free])
    near = np.ones(len(pix), bool)
    for a in range(3):
        near &= (objects.tri_lo[tri, a] <= hi[pix, a]) & (objects.tri_hi[tri, a] >= lo[pix, a])
    near &= tri != own[pix]
    pix, tri = pix[near], tri[near]
    keep = _keep(objects, corners, p, normal, own, pix, tri, None)
    pix, tri = pix[keep], tri[keep]
    m = pyramid.sides(light, p, base)
    _, _, pix, tri, _ = pyramid.cut(light, corners, p, pix, tri, base, m, store=False)
    pix, tri = np.r_[whole[0], pix], np.r_[whole[1], tri]
    order = np.argsort(pix, kind="stable")
    pix, tri = pix[order], tri[order]
    flat, free = pyramid.uncut(light, corners, p, pix, tri)
    return flat, free, pix, tri
