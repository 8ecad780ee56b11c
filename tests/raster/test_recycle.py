"""The arrays a frame returns come from `recycle.ArrayPool`: memory is reused only once nothing
the caller can reach refers to it, so no array a caller holds ever changes under it."""

from __future__ import annotations

import gc

import numpy as np
import pytest

from shadowvol.primitives import plane, sphere
from shadowvol.raster.recycle import ArrayPool
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import AreaLight, Camera, Material, PointLight, Scene


def scene_of(seed: int, lights: int) -> Scene:
    """A floor and spheres under `lights` point lights, small."""
    rng = np.random.default_rng(seed)
    balls = [sphere(f"s{i}", [rng.uniform(-2, 2), rng.uniform(0.5, 1.5), rng.uniform(-2, 1)],
                    rng.uniform(0.3, 0.7), Material(diffuse=rng.uniform(0.2, 0.9, 3)),
                    subdivisions=2) for i in range(3)]
    return Scene(camera=Camera(eye=[0, 4, 9], target=[0, 0.8, 0]),
                 objects=[plane("floor", size=[12, 12])] + balls,
                 lights=[PointLight([rng.uniform(-4, 4), rng.uniform(5, 8), rng.uniform(-2, 4)],
                                    intensity=0.3) for _ in range(lights)],
                 width=96, height=72)


def test_an_array_is_reused_only_when_nothing_else_refers_to_it():
    pool = ArrayPool()
    a = pool.empty((4, 5), np.float32)
    b = pool.empty((4, 5), np.float32)
    assert a is not b and a.shape == (4, 5) and a.dtype == np.float32
    kept_id = id(a)
    del a
    assert id(pool.empty((4, 5), np.float32)) == kept_id   # dropped: handed out again
    c = pool.empty((4, 5), np.float32)
    for holder in (lambda x: x[1:], lambda x: memoryview(x), lambda x: np.frombuffer(x, np.uint8),
                   lambda x: {"result": x}):
        held = holder(c)
        c_id = id(c)
        del c
        others = [pool.empty((4, 5), np.float32) for _ in range(3)]
        assert all(id(o) != c_id for o in others), holder
        del others
        c = pool.empty((4, 5), np.float32)   # not necessarily the same one again
        del held
    # other shapes and dtypes are other arrays
    assert pool.empty((4, 5), np.float64).dtype == np.float64
    assert pool.empty((5, 4), np.float32).shape == (5, 4)


def test_at_most_keep_arrays_are_kept_per_shape():
    pool = ArrayPool()
    held = [pool.empty((3,), bool) for _ in range(ArrayPool.KEEP + 4)]
    assert len({id(x) for x in held}) == len(held)
    assert len(pool._kept[((3,), np.dtype(bool).str)]) == ArrayPool.KEEP
    pool.clear()
    assert not pool._kept


OUT = ("image", "image_srgb", "lit", "coverage")
OUTPUTS = OUT


@pytest.mark.parametrize("lights", [1, 3])
def test_kept_frames_never_change_and_dropped_ones_are_reused(ctx, lights):
    scene = scene_of(3, lights=lights)
    moved = [PointLight(np.array([1.5, 6.0, 2.0]) + k, intensity=0.3) for k in range(lights)]
    with Renderer(scene, ctx) as r:
        first = r.render(outputs=OUTPUTS)
        snapshot = {k: getattr(first, k).copy() for k in OUT}
        # frames of other lights while `first` is held: `first` is never written
        for _ in range(ArrayPool.KEEP + 1):
            other = r.render(lights=tuple(moved), outputs=OUTPUTS)
            assert not np.array_equal(other.lit, first.lit)
        for k in OUT:
            np.testing.assert_array_equal(getattr(first, k), snapshot[k], err_msg=k)
        # a frame dropped before the next: its memory comes back, and the frame is the same
        addresses = {k: getattr(first, k).ctypes.data for k in OUT}
        del first, other
        gc.collect()
        again = r.render(outputs=OUTPUTS)
        for k in OUT:
            np.testing.assert_array_equal(getattr(again, k), snapshot[k], err_msg=k)
        assert {k: getattr(again, k).ctypes.data for k in OUT} == addresses


def test_one_kept_array_keeps_only_its_own_memory(ctx):
    with Renderer(scene_of(4, lights=2), ctx) as r:
        lit = r.render().lit          # the rest of the frame is dropped
        snapshot = lit.copy()
        for _ in range(ArrayPool.KEEP + 1):
            r.render(lights=(PointLight([0.0, 7.0, 0.0], intensity=0.3),) * 2)
        np.testing.assert_array_equal(lit, snapshot)


def test_an_area_lights_counts_start_from_zero_in_reused_memory(ctx):
    scene = scene_of(5, lights=1)
    area = AreaLight(shape="rect", center=[0.0, 6.0, 1.0], normal=[0, -1.0, 0], size=[1.0, 1.0],
                     samples=9, intensity=0.3)
    with Renderer(scene, ctx) as r:
        want = r.render(lights=(area,)).lit_count.copy()
        for _ in range(3):   # the memory of the frames before holds other counts
            r.render(lights=(PointLight([0.0, 6.0, 1.0], intensity=0.3),))
            np.testing.assert_array_equal(r.render(lights=(area,)).lit_count, want)

