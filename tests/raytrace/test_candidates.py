"""The exact visibility's candidate query (`raytrace.candidates`): in numba
(`raytrace.exactkernels`) the same clusters and pairs, in the same order, as numpy's; and
conservative against brute force: every triangle the pyramid cut leaves something of (all
pairs cut, float64) is a candidate of its pixel.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest
import trimesh

from raytrace import candidates, pyramid
from raytrace.lightshapes import FramedLight
from raytrace.occluders import objects
from shadowvol.planes import default_plane_axes

pytest.importorskip("numba")


def _setup(seed: int):
    """A tilted rect light, points below it, and a soup of small triangles in three objects
    between and around (so some clusters meet a pyramid only by their boxes), a closed ball
    and a convex body with a third of the points on it."""
    rng = np.random.default_rng(seed)
    normal = np.array([0.2, -1.0, 0.3]) / np.linalg.norm([0.2, -1.0, 0.3])
    u, v = default_plane_axes(normal)
    hull = np.array([[-0.5, -0.3], [0.5, -0.3], [0.5, 0.3], [-0.5, 0.3]])
    light = FramedLight(np.array([0.1, 2.0, -0.2]), normal, np.stack([u, v]), hull, None, None,
                        0.6, 2.0 ** -44)
    base = light.center + hull @ light.axes
    n, m = 50, 900
    p = np.c_[rng.uniform(-1.5, 1.5, n), rng.uniform(-0.2, 0.2, n), rng.uniform(-1.5, 1.5, n)]
    centre = np.c_[rng.uniform(-2, 2, m), rng.uniform(-0.3, 2.3, m), rng.uniform(-2, 2, m)]
    corners = centre[:, None] + rng.normal(0, 0.12, (m, 3, 3))
    ids = rng.integers(0, 3, m)
    # a closed, not convex, object too: a noisy ball between the points and the light
    ico = trimesh.creation.icosphere(subdivisions=2, radius=0.5)
    ball = ico.vertices * (1 + 0.15 * rng.standard_normal((len(ico.vertices), 1))) + [0, 1, 0]
    # and a convex one, some points on its faces (their own object, seen from outside)
    body = trimesh.creation.icosphere(subdivisions=1, radius=0.3)
    shell = body.vertices[body.faces] + [0.6, 0.0, 0.6]
    corners = np.concatenate([corners, ball[ico.faces], shell])
    ids = np.r_[ids, np.full(len(ico.faces), 3), np.full(len(shell), 4)]
    own = rng.integers(0, len(corners), n)
    on = rng.choice(n, n // 3, replace=False)
    own[on] = len(corners) - len(shell) + rng.integers(0, len(shell), len(on))
    p[on] = corners[own[on]].mean(axis=1)
    lo = np.minimum(p, base.min(axis=0))
    hi = np.maximum(p, base.max(axis=0))
    obj = objects(corners, ids)
    assert obj.convex[-1] and not obj.convex[-len(shell) - 1]
    return light, base, obj, corners, p, own, lo, hi


@pytest.mark.parametrize("seed", range(4))
def test_the_kernels_find_numpys_clusters_and_pairs(seed, monkeypatch):
    light, base, obj, corners, p, own, lo, hi = _setup(seed)
    normal = np.tile([0.0, 1.0, 0.0], (len(p), 1))
    mine = obj.convex[own]
    normal[mine] = obj.outward[own[mine]]                   # outside the convex object
    clear = np.array([True, False, True, True, True])      # the light outside the ball
    fast_meet = candidates.meets(light, obj, p, base, lo, hi)
    fast = [candidates.pairs(obj, corners, p, normal, own, fast_meet, lo, hi, c)
            for c in (None, clear)]
    # only the clusters among those asked about (a block's: `blockwindings.chains`)
    among = np.random.default_rng(seed).random(fast_meet.shape) < 0.5
    fast_among = candidates.meets(light, obj, p, base, lo, hi, among)
    np.testing.assert_array_equal(fast_among, fast_meet & among)
    monkeypatch.setitem(sys.modules, "raytrace.exactkernels", None)    # import fails: numpy
    slow_meet = candidates.meets(light, obj, p, base, lo, hi)
    np.testing.assert_array_equal(candidates.meets(light, obj, p, base, lo, hi, among),
                                  slow_meet & among)
    slow = [candidates.pairs(obj, corners, p, normal, own, slow_meet, lo, hi, c)
            for c in (None, clear)]
    assert slow_meet.any() and not slow_meet.all()
    np.testing.assert_array_equal(fast_meet, slow_meet)
    assert len(slow[1][0]) > 100
    assert len(slow[1][0]) < len(slow[0][0])            # the ball's faces toward p left out
    for f, w in zip(fast, slow):
        for got, want in zip(f, w):
            assert got.dtype == want.dtype and np.array_equal(got, want)


@pytest.mark.parametrize("seed", range(4))
def test_every_triangle_the_cut_keeps_is_a_candidate(seed):
    light, base, obj, corners, p, own, lo, hi = _setup(seed)
    normal = np.tile([0.0, 1.0, 0.0], (len(p), 1))
    mine = obj.convex[own]
    normal[mine] = obj.outward[own[mine]]
    meet = candidates.meets(light, obj, p, base, lo, hi)
    pix, tri = candidates.pairs(obj, corners, p, normal, own, meet, lo, hi)
    found = set(zip(pix.tolist(), tri.tolist()))
    every_pix = np.repeat(np.arange(len(p)), len(corners))
    every_tri = np.tile(np.arange(len(corners)), len(p))
    _, _, kept_pix, kept_tri, _ = pyramid.cut(light, corners, p, every_pix, every_tri, base)
    # less p's own triangle and, by design, its convex object's from outside (they lie
    # behind p's tangent plane, whose far side of the light is taken away whole)
    behind = obj.convex[kept_tri] & (obj.object[kept_tri] == obj.object[own[kept_pix]])
    want = {(i, t) for i, t, b in zip(kept_pix.tolist(), kept_tri.tolist(), behind)
            if t != own[i] and not b}
    assert len(want) > 50
    assert want <= found
    assert len(found) < len(p) * len(corners) / 2          # and the query does cull
