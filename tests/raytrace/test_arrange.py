"""`arrange.union` (a crowded pixel's union of shadows from its outline) against GEOS's cascaded
union of the same pieces, where the cut pieces' edges run along the light's box a few
roundings off it, as the pyramid's side planes leave them: GEOS's floating noder can leave
such an arrangement unnoded and its polygonizer then drops a face (seen: 5 % of a light lost
on one pixel of tests/raytrace/test_exact_fast.py's first scene).
"""

from __future__ import annotations

import numpy as np
import pytest

from raytrace import arrange

shapely = pytest.importorskip("shapely")


def _crowd(seed: int):
    """Cut pieces: random triangles clipped to the box, each corner on its edge moved a few
    float64 spacings off it; free pieces: small whole triangles inside, some across the box."""
    rng = np.random.default_rng(seed)
    half = rng.uniform(0.3, 1.0, 2)
    box = np.stack([-half, half])
    frame = shapely.box(*box[0], *box[1])
    cut = []
    for _ in range(rng.integers(3, 7)):
        tri = shapely.Polygon(rng.uniform(-2.5, 2.5, (3, 2)) * half)
        piece = shapely.clip_by_rect(tri, *box[0], *box[1])
        if piece.is_empty or piece.area == 0:
            continue
        xy = np.array(piece.exterior.coords)[:-1]
        on = np.isclose(np.abs(xy), half[None], rtol=0, atol=1e-12)
        ulps = rng.integers(-8, 9, xy.shape) * np.spacing(half)[None]
        cut.append(xy + np.where(on, ulps, 0.0))
    q = len(cut) + 30
    width = max(len(c) for c in cut) if cut else 3
    flat = np.zeros((q, max(width, 3), 2))
    count = np.zeros(q, np.int64)
    for i, c in enumerate(cut):
        flat[i, :len(c)], count[i] = c, len(c)
    uncut = np.zeros((q, 3, 2))
    centre = rng.uniform(-1.1, 1.1, (30, 1, 2)) * half
    uncut[len(cut):] = centre + rng.normal(0, 0.15, (30, 3, 2)) * half
    free = np.arange(q) >= len(cut)
    ids = np.arange(3 * q).reshape(q, 3)
    return flat, count, uncut, free, ids, box, frame


def _cascaded(flat, count, uncut, free, frame):
    polys = [shapely.Polygon(uncut[i]) if free[i] else shapely.Polygon(flat[i, :count[i]])
             for i in range(len(free))]
    return shapely.union_all(polys).intersection(frame)


@pytest.mark.parametrize("seed", range(40))
def test_the_outline_union_is_the_cascaded_union_along_the_lights_edges(seed):
    flat, count, uncut, free, ids, box, frame = _crowd(seed)
    grid = 2.0 ** -44 * 2.0 ** np.ceil(np.log2(np.abs(box).max()))
    got = arrange.union(shapely, flat, count, uncut, free, ids, box, grid)
    want = _cascaded(flat, count, uncut, free, frame)
    assert want.area > 0
    assert abs(got.intersection(frame).area - want.area) <= 1e-11 * frame.area
