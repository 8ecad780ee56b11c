"""`pyramid.cut`, `pyramid.uncut` and `regions.inside` in numba (`raytrace.exactkernels`;
the candidate query's kernels: tests/raytrace/test_candidates.py) against their numpy paths,
byte for byte: the decided triangles (wholly outside a plane, wholly inside all), the
clipped ones and the whole shadows, on random triangles around the pyramid and on ties
(corners on the side planes, at p, at the light's corners); and the exact visibility of a
closed mesh the same bytes with and without them.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

from raytrace import polygons, pyramid, regions
from raytrace.lightshapes import FramedLight
from shadowvol.planes import default_plane_axes

pytest.importorskip("numba")


def _light() -> FramedLight:
    """A rect light tilted off every axis (so no side plane's normal has a zero component and
    the order of a dot product's sum shows in its bits)."""
    normal = np.array([0.2, -1.0, 0.3]) / np.linalg.norm([0.2, -1.0, 0.3])
    u, v = default_plane_axes(normal)
    hull = np.array([[-0.5, -0.3], [0.5, -0.3], [0.5, 0.3], [-0.5, 0.3]])
    return FramedLight(np.array([0.1, 2.0, -0.2]), normal, np.stack([u, v]), hull, None, None,
                       0.6, 2.0 ** -44)


def _pairs(seed: int):
    """Points below the light, triangles around and across their pyramids, and pairs of
    them: random corners, corners on side planes and at p, corners at the light's."""
    rng = np.random.default_rng(seed)
    light = _light()
    base = light.center + light.hull @ light.axes
    n, q = 40, 1200
    p = np.c_[rng.uniform(-1, 1, n), rng.uniform(-0.5, 0.5, n), rng.uniform(-1, 1, n)]
    pix = rng.integers(0, n, q)
    tri = rng.permutation(q)                        # a triangle a pair, in no order
    corners = np.c_[rng.uniform(-1.5, 1.5, (q, 3, 1)), rng.uniform(-0.6, 2.4, (q, 3, 1)),
                    rng.uniform(-1.5, 1.5, (q, 3, 1))]
    # small ones about a point of the pyramid: inside, or across a side plane
    toward = base[rng.integers(0, len(base), q)] * 0.7 + light.center * 0.3
    at = p[pix] + rng.uniform(0.1, 0.9, (q, 1)) * (toward - p[pix])
    small = rng.random(q) < 0.5
    corners[tri[small]] = at[small, None] + rng.normal(0, 0.08, (int(small.sum()), 3, 3))
    # ties: a corner on the segment from p to a light's corner (two side planes), or at p
    for r in rng.choice(q, q // 4, replace=False):
        j, s = rng.integers(0, len(base)), rng.choice([0.0, 0.25, 0.5, 1.0])
        corners[tri[r], rng.integers(0, 3)] = p[pix[r]] + s * (base[j] - p[pix[r]])
    return light, base, corners, p, pix, tri


@pytest.mark.parametrize("seed", range(6))
def test_the_kernel_cuts_numpys_bytes(seed, monkeypatch):
    light, base, corners, p, pix, tri = _pairs(seed)
    fast = pyramid.cut(light, corners, p, pix, tri, base)
    monkeypatch.setitem(sys.modules, "raytrace.exactkernels", None)    # import fails: numpy
    slow = pyramid.cut(light, corners, p, pix, tri, base)
    whole, count = slow[4], slow[1]
    assert whole.any() and (~whole).any() and (count > 3).any()      # every kind of row
    assert len(slow[1]) < len(pix)                                    # and some dropped
    for got, want in zip(fast, slow):
        assert got.dtype == want.dtype and got.shape == want.shape
        assert got.tobytes() == want.tobytes()


@pytest.mark.parametrize("kernel", [True, False])
@pytest.mark.parametrize("seed", range(3))
def test_a_cut_without_pieces_then_some_rows_pieces_is_the_whole_cut(seed, kernel, monkeypatch):
    """`exact_soft` asks the cut which pairs keep something without storing their pieces
    (`store=False`), then `pyramid.pieces` for the rows it carries: the same kept pairs, counts
    and whole flags, and those rows' pieces the same bytes as the one cut's, at its width."""
    light, base, corners, p, pix, tri = _pairs(seed)
    if not kernel:
        monkeypatch.setitem(sys.modules, "raytrace.exactkernels", None)
    pieces, count, at_pix, at_tri, whole = pyramid.cut(light, corners, p, pix, tri, base)
    m = pyramid.sides(light, p, base)
    none, *kept = pyramid.cut(light, corners, p, pix, tri, base, m, store=False)
    assert none is None
    for got, want in zip(kept, (count, at_pix, at_tri, whole)):
        assert got.dtype == want.dtype and got.tobytes() == want.tobytes()
    rows = np.random.default_rng(seed).permutation(len(count))[:len(count) // 2]
    rows = np.r_[rows, np.flatnonzero(count == count.max())[:1]]       # the widest too
    some = pyramid.pieces(light, corners, p, at_pix[rows], at_tri[rows], m, pieces.shape[1])
    assert some.shape == (len(rows),) + pieces.shape[1:]
    assert some.tobytes() == pieces[rows].tobytes()


@pytest.mark.parametrize("seed", range(4))
def test_the_kernel_carries_numpys_whole_shadows(seed, monkeypatch):
    """`uncut`: the whole shadows, and which are free (between the two planes, in reach)."""
    light, base, corners, p, pix, tri = _pairs(seed)
    corners = corners * [1.0, 0.5, 1.0] + [0.0, 0.9, 0.0]     # many between the planes
    fast = pyramid.uncut(light, corners, p, pix, tri)
    monkeypatch.setitem(sys.modules, "raytrace.exactkernels", None)
    slow = pyramid.uncut(light, corners, p, pix, tri)
    assert slow[1].sum() > 100 and (~slow[1]).sum() > 100
    for got, want in zip(fast, slow):
        assert got.dtype == want.dtype and got.tobytes() == want.tobytes()


def test_the_pieces_lie_in_the_pyramid_and_whole_ones_are_their_triangles():
    """A witness of the clip apart from either path: every kept corner is inside every plane
    (to the rounding of its interpolation), a whole piece is its triangle, and a pair with a
    corner strictly inside all planes is kept."""
    light, base, corners, p, pix, tri = _pairs(7)
    pieces, count, at_pix, at_tri, whole = pyramid.cut(light, corners, p, pix, tri, base)
    sides = pyramid.sides(light, p, base)
    scale = np.abs(corners).max() * 8 * np.finfo(float).eps
    for r in range(len(count)):
        poly = pieces[r, :count[r]]
        assert ((poly - light.center) @ light.normal >= -scale * 4).all()
        for m in sides:
            u = m[at_pix[r]]
            assert ((poly - p[at_pix[r]]) @ u >= -scale * 4 * np.linalg.norm(u)).all()
        assert not pieces[r, count[r]:].any()
        if whole[r]:
            assert np.array_equal(poly, corners[at_tri[r]])
    dist = [(corners[tri] - light.center) @ light.normal] + \
        [np.einsum("qkj,qj->qk", corners[tri] - p[pix][:, None], m[pix]) for m in sides]
    inner = np.logical_and.reduce([d > 1e-9 for d in dist])          # (q, 3) per corner
    assert inner.any(axis=1).sum() > 20
    kept = set(zip(at_pix.tolist(), at_tri.tolist()))
    for r in np.flatnonzero(inner.any(axis=1)):
        assert (pix[r], tri[r]) in kept


def test_exact_visibility_is_the_same_bytes_without_the_kernel(monkeypatch):
    """A closed non-convex mesh's penumbra (the cut's hot path) with and without numba."""
    import trimesh

    from builders import FLOOR_Y, LIGHT_Y, MATTE
    from raytrace.exact_soft import exact_visibility
    from shadowvol.primitives import mesh, plane
    from shadowvol.scene import AreaLight, Camera, Scene
    rng = np.random.default_rng(3)
    ico = trimesh.creation.icosphere(subdivisions=2, radius=0.4)
    v = ico.vertices * (1 + 0.15 * rng.standard_normal((len(ico.vertices), 1)))
    light = AreaLight("rect", [0.0, LIGHT_Y, 0.0], normal=[0.1, -1, 0.2], size=[1.0, 0.7],
                      samples=4)
    objects = [plane("floor", point=[0.0, FLOOR_Y, 0.0], size=[8.0, 8.0], material=MATTE),
               mesh("ball", v + [0.2, -v[:, 1].min() + 0.3, 0.1], ico.faces, MATTE)]
    camera = Camera(eye=[0.0, 4.5, 5.5], target=[0.0, 0.3, -0.3], fov_y=40.0)
    scene = Scene(camera=camera, objects=objects, lights=[light], width=32, height=32,
                  ambient=[0.0, 0.0, 0.0])
    fast = exact_visibility(scene)
    monkeypatch.setitem(sys.modules, "raytrace.exactkernels", None)
    slow = exact_visibility(scene)
    assert 0 < (fast.visibility[0] > 0).sum() and ((fast.visibility > 0) &
                                                   (fast.visibility < 1)).sum() > 20
    for got, want in zip(fast[:2], slow[:2]):
        assert got.tobytes() == want.tobytes()


def _polygons_to_clip(seed: int) -> tuple[np.ndarray, ...]:
    """Triangles (some of no area) and convex polygons of 3 to 6 counter-clockwise corners
    to clip them by, some of the triangles' corners on the polygons' first edges."""
    rng = np.random.default_rng(seed)
    n = 500
    count = rng.integers(3, 7, n)
    angle = np.sort(rng.uniform(0, 2 * np.pi, (n, 6)), axis=1)
    cut = np.stack([np.cos(angle), np.sin(angle)], axis=-1) * rng.uniform(0.5, 1.5, (n, 1, 1))
    cut[np.arange(6)[None] >= count[:, None]] = 0.0
    inner = rng.uniform(-1.6, 1.6, (n, 3, 2))
    on = rng.random(n) < 0.2            # a corner on the polygon's first edge
    inner[on, 0] = cut[on, 0] + rng.uniform(0, 1, (int(on.sum()), 1)) * (cut[on, 1] - cut[on, 0])
    inner_count = np.where(rng.random(n) < 0.1, 0, 3)
    return cut, count, inner, inner_count


@pytest.mark.parametrize("room", [0, 1])
@pytest.mark.parametrize("seed", range(3))
def test_a_clip_with_no_room_is_done_again_to_the_same_corners(seed, room):
    """`exactkernels.inside` started with no room (0: every row goes round again in more)
    or room for m + k corners gives the same corners and counts as with room to spare."""
    loaded = polygons.kernels()
    args = _polygons_to_clip(seed)
    want = loaded.inside(*args, 4)
    got = loaded.inside(*args, room)
    assert got[0].shape[1] >= args[2].shape[1] + args[0].shape[1] or room == 0
    np.testing.assert_array_equal(got[1], want[1])
    most = int(want[1].max())
    keep = np.arange(most)[None] < want[1][:, None]
    assert got[0][:, :most][keep].tobytes() == want[0][:, :most][keep].tobytes()


@pytest.mark.parametrize("seed", range(4))
def test_the_kernel_clips_numpys_polygons_inside(seed, monkeypatch):
    """`regions.inside`: triangles (some of no area) clipped by convex polygons of 3 to 6
    counter-clockwise corners, some corners on their edges; the corners up to each count."""
    cut, count, inner, inner_count = _polygons_to_clip(seed)
    fast = regions.inside(cut, count, inner, inner_count)
    monkeypatch.setitem(sys.modules, "raytrace.exactkernels", None)
    slow = regions.inside(cut, count, inner, inner_count)
    np.testing.assert_array_equal(fast[1], slow[1])
    assert (slow[1] > 3).any() and (slow[1] == 0).any() and (slow[1] == 3).any()
    keep = np.arange(slow[0].shape[1])[None] < slow[1][:, None]
    assert fast[0][keep].tobytes() == slow[0][keep].tobytes()
