"""Embree's packets (`raytrace.embree.PacketBackend`: rtcIntersect8/rtcOccluded8 through numba
on the library the embreex wheel ships) answer as embreex's single rays (`EmbreeBackend`) do, bit
for bit: every query on random soups, with rays aimed at shared vertices and edges (where the
order of the walk picks between tied triangles), and the masks and the ground truth of random
scenes (tests/strategies.py: coordinates on a grid of sixteenths, so exact ties and coplanar
triangles are common), of the grazing walls and of the example scenes.  A planted lane swap in
the packets' write-back shows the comparison catches a difference.

The rest of the mask tests run with whichever path $SHADOWVOL_EMBREE chooses (packets by
default): run them again with SHADOWVOL_EMBREE=single for the single-ray path.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from strategies import grazing_scenes, profile, scenes

import raytrace
from raytrace.embree import EmbreeBackend, PacketBackend, embree_queries
from raytrace.groundtruth import ground_truth
from shadowvol.resources import example_scene
from shadowvol.scene import SceneError
from shadowvol.scenefile import load_scene

pytest.importorskip("numba", reason="the packets need numba (pip install 'shadowvol[fast]')")
if embree_queries("auto") != "packets":
    pytest.skip("the embreex wheel ships no Embree 4 library here", allow_module_level=True)

SCENES = ("cage.toml", "stack.toml", "inside_shadow.toml", "whitted.toml")


def soup_with_ties(rng, m=800):
    """m random triangles, each sharing an edge with the next (a fan of shared edges and
    vertices): vertices (m + 2, 3), faces (m, 3)."""
    v = rng.integers(-48, 48, (m + 2, 3)) / 16.0
    f = np.stack([np.arange(m), np.arange(1, m + 1), np.arange(2, m + 2)], axis=1)
    return v, f


def rays_at(rng, v, f, n):
    """n rays from random origins toward shared vertices, edge midpoints and random points."""
    o = rng.integers(-96, 96, (n, 3)) / 16.0
    a, b = v[f[:, 0]], v[f[:, 1]]
    k = rng.integers(0, len(f), n)
    kind = rng.integers(0, 3, n)
    target = np.where(kind[:, None] == 0, a[k], np.where(kind[:, None] == 1, (a[k] + b[k]) / 2,
                                                       rng.uniform(-3, 3, (n, 3))))
    return o, target - o


@pytest.mark.parametrize("parallel", [False, True])
def test_every_query_equals_single_rays(parallel):
    rng = np.random.default_rng(7)
    v, f = soup_with_ties(rng)
    single, packets = EmbreeBackend(v, f), PacketBackend(v, f)
    o, d = rays_at(rng, v, f, 40_000)
    bound = rng.uniform(0.2, 1.2, len(o))
    for tmax in (None, 0.9, bound):
        assert np.array_equal(single.closest_triangle(o, d, tmax, parallel),
                              packets.closest_triangle(o, d, tmax, parallel))
        assert np.array_equal(single.occluded(o, d, tmax, parallel),
                              packets.occluded(o, d, tmax, parallel))
    one = d[:1] / np.linalg.norm(d[0])  # one direction for all, as toward a directional light
    assert np.array_equal(single.occluded(o, one, None, parallel),
                          packets.occluded(o, one, None, parallel))
    for tmax in (None, bound):
        s, p = single.first_hit(o, d, tmax), packets.first_hit(o, d, tmax)
        assert np.array_equal(s.tri, p.tri) and np.array_equal(s.t, p.t)
        assert s.t.dtype == p.t.dtype == np.float32
    assert (single.closest_triangle(o, d) >= 0).mean() > 0.3   # the rays meet the soup


def test_component_major_rays_equal_rows():
    """The masks hand over (3, n) arrays transposed: strided rays, the same answers."""
    rng = np.random.default_rng(3)
    v, f = soup_with_ties(rng, 200)
    packets = PacketBackend(v, f)
    o, d = rays_at(rng, v, f, 5000)
    o32, d32 = np.ascontiguousarray(o.T, np.float32), np.ascontiguousarray(d.T, np.float32)
    assert np.array_equal(packets.closest_triangle(o32.T, d32.T), packets.closest_triangle(o, d))


def _both_ways(monkeypatch, trace):
    """trace() with the single rays, then with the packets."""
    monkeypatch.setenv("SHADOWVOL_EMBREE", "single")
    single = trace()
    monkeypatch.setenv("SHADOWVOL_EMBREE", "packets")
    return single, trace()


def _mismatches(monkeypatch, scene) -> int:
    """Values where the packets' masks, coverage and ground truth (lit, coverage, depth,
    distance, normal, object id, facing count, casters) differ from the single rays'."""
    (lit_s, cov_s), (lit_p, cov_p) = _both_ways(monkeypatch, lambda: raytrace.shadow_masks(scene))
    truth_s, truth_p = _both_ways(monkeypatch, lambda: ground_truth(scene))
    out = int((lit_s != lit_p).sum() + (cov_s != cov_p).sum())
    for name in ("lit", "coverage", "depth", "distance", "normal", "object_id", "facing_count",
                 "casters"):
        a, b = getattr(truth_s, name), getattr(truth_p, name)
        assert a is not None and a.shape == b.shape, name
        out += int((a.view(np.uint8) != b.view(np.uint8)).sum())   # bits, NaN and -0.0 too
    return out


@profile()
@given(scene=scenes())
def test_random_scenes_bit_for_bit(monkeypatch, scene):
    assert _mismatches(monkeypatch, scene) == 0


@profile()
@given(scene=grazing_scenes())
def test_grazing_scenes_bit_for_bit(monkeypatch, scene):
    assert _mismatches(monkeypatch, scene) == 0


@pytest.mark.parametrize("name", SCENES)
def test_example_scenes_bit_for_bit(monkeypatch, name):
    scene = _small(name)
    assert _mismatches(monkeypatch, scene) == 0


def test_a_planted_lane_swap_is_caught(monkeypatch):
    """The comparison can fail: packets whose write-back swaps two lanes of every packet (a
    bug a packet path can have) differ from the single rays on an example scene."""
    scene = _small("cage.toml")
    run = PacketBackend._run

    def swapped(self, *args):
        out = run(self, *args).copy()
        n = len(out) - len(out) % 16
        out[:n].reshape(-1, 16)[:, [0, 1]] = out[:n].reshape(-1, 16)[:, [1, 0]]
        return out

    assert _mismatches(monkeypatch, scene) == 0
    monkeypatch.setattr(PacketBackend, "_run", swapped)
    assert _mismatches(monkeypatch, scene) > 0


def _small(name):
    """The example scene `name`, 160 x 120."""
    return load_scene(example_scene(name)).replace(width=160, height=120)


def test_the_switch(monkeypatch):
    assert embree_queries("single") == "single" and embree_queries("packets") == "packets"
    monkeypatch.setenv("SHADOWVOL_EMBREE", "sideways")
    with pytest.raises(SceneError, match="SHADOWVOL_EMBREE"):
        embree_queries()
    monkeypatch.setenv("SHADOWVOL_EMBREE", "single")
    assert isinstance(raytrace.backends.make_backend("embree", *soup_with_ties(
        np.random.default_rng(1), 4)), EmbreeBackend)
