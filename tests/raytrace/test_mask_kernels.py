"""The masks' numba kernels (`raytrace.maskkernels`, the packet path) make the arrays that
numpy makes (`raytrace.masks`), bit for bit: every field of the primary hits of every tile, and
the shadow segments and near pieces toward point, spot and directional lights, on random and
grazing scenes (tests/strategies.py).  tests/raytrace/test_packets.py compares the masks and the
ground truth of the two paths as a whole."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from strategies import grazing_scenes, profile, scenes

from raytrace.camera import RayGrid
from raytrace.embree import PacketBackend, embree_queries
from raytrace.masks import _local_light, _primary_hits, _segments, scene_backend

pytest.importorskip("numba", reason="the kernels need numba (pip install 'shadowvol[fast]')")
if embree_queries("auto") != "packets":
    pytest.skip("the embreex wheel ships no Embree 4 library here", allow_module_level=True)


class _NumpyPath:
    """A packet backend that `masks` does not recognise as one: its numpy path."""

    def __init__(self, tracer):
        self._tracer = tracer

    def __getattr__(self, name):
        return getattr(self._tracer, name)


def _same(a, b, name, out):
    """Append name to out where arrays a and b differ in dtype, shape or bits."""
    if a is None or b is None:
        if a is not b:
            out.append(name)
    elif a.dtype != b.dtype or a.shape != b.shape or not np.array_equal(
            np.ascontiguousarray(a).view(np.uint8), np.ascontiguousarray(b).view(np.uint8)):
        out.append(name)


def _differences(scene, rows_per_tile=7) -> list[str]:
    """The arrays where the kernels and numpy differ, over every tile and light of scene."""
    backend = scene_backend(scene, "embree")
    assert isinstance(backend.tracer, PacketBackend)
    camera = scene.camera.translated(-backend.origin)
    grids = tuple(RayGrid(camera, scene.width, scene.height, t) for t in (np.float32,
                                                                           np.float64))
    lights = [_local_light(light, backend.origin, backend.triangles) for light in scene.lights]
    out = []
    for y in range(0, scene.height, rows_per_tile):
        rows = slice(y, min(y + rows_per_tile, scene.height))
        mine = _primary_hits(backend.tracer, backend.triangles, grids, rows)
        theirs = _primary_hits(_NumpyPath(backend.tracer), backend.triangles, grids, rows)
        _same(mine[0], theirs[0], "covered", out)
        _same(mine[1], theirs[1], "index", out)
        if (mine[2] is None) != (theirs[2] is None):
            out.append("hits")
        if mine[2] is None or theirs[2] is None:
            continue
        for name, a, b in zip(mine[2]._fields, mine[2], theirs[2]):
            _same(a, b, f"hit.{name}", out)
        for local in lights:
            fused = _segments(local, theirs[2], scene.extent, True)
            plain = _segments(local, theirs[2], scene.extent)
            for name in ("facing", "rays", "start", "direction", "tmax"):
                _same(getattr(fused, name), getattr(plain, name), name, out)
            for name in fused.near._fields:
                _same(getattr(fused.near, name), getattr(plain.near, name), f"near.{name}",
                      out)
    return out


@profile()
@given(scene=scenes())
def test_random_scenes_bit_for_bit(scene):
    assert _differences(scene) == []


@profile()
@given(scene=grazing_scenes())
def test_grazing_scenes_bit_for_bit(scene):
    assert _differences(scene) == []


def test_through_light_equals_numpy():
    """`maskkernels.through_light` is `tolerances.through_light`, to the bit: random triangles,
    lights on some of their planes (a weight found), off all of them (0.0), and far away."""
    from raytrace.maskkernels import through_light as kernel
    from raytrace.tolerances import through_light
    from raytrace.triangles import TriangleSet

    rng = np.random.default_rng(5)
    for scale in (1.0, 1e-3, 1e5):
        v = rng.integers(-64, 64, (600, 3)) / 16.0 * scale
        tris = TriangleSet(v, rng.integers(0, len(v), (400, 3)))
        on = [v[f].mean(axis=0) for f in tris.faces[:20]]   # on a triangle's plane
        for light in on + list(rng.uniform(-8, 8, (20, 3)) * scale):
            light = np.asarray(light, np.float64)
            want = through_light(tris.normals, tris.plane_d, tris.weight, light)
            got = kernel(np.ascontiguousarray(tris.normals.T), tris.plane_d, tris.weight,
                         light)
            assert np.float64(got).tobytes() == np.float64(want).tobytes()
        assert any(through_light(tris.normals, tris.plane_d, tris.weight, p) > 0 for p in on)
