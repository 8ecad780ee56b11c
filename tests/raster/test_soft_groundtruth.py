"""Both renderers' ground truth for area lights of every shape (rect, disk, sphere) beside hard
lights, on a scene of this file: `lit_count` and `facing_count` under the counts' budget
(tests/builders.py `check_counts`, `check_facing_counts`), `facing`, `cast` and every bit of
`casters` under the masks' budget (no mismatch off an edge, one pixel, of that mask in either
or of the object ids; few in all), and in both `casters.any(-1) == (lit_count <
facing_count)`, `facing == (facing_count > 0)`, `lit == (lit_count == N)`, and the umbra and
penumbra of docs/CONVENTIONS.md equal to `raytrace.soft_masks`'."""

from __future__ import annotations

import numpy as np
import pytest
from builders import check_counts, check_facing_counts

import raytrace
from shadowvol.compare.maskdiff import edge_pixels
from shadowvol.frame import decode_casters
from shadowvol.frame import GROUND_TRUTH
from shadowvol.primitives import box, plane, sphere
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import AreaLight, Camera, PointLight, Scene, SpotLight

pytestmark = pytest.mark.gl

MAX_MISMATCH_FRACTION = 0.001


def every_shape_scene(width: int = 96, height: int = 72) -> Scene:
    lights = (
        AreaLight("rect", [-0.8, 3.0, 0.4], normal=[0.3, -1.0, 0.0], size=[0.8, 0.5],
                  samples=9, seed=2),
        AreaLight("disk", [0.9, 2.6, -0.3], normal=[0.0, -1.0, 0.2], radius=0.35, samples=8,
                  pattern="halton"),
        AreaLight("sphere", [0.2, 2.2, 1.2], radius=0.25, samples=6, seed=4),
        PointLight([1.5, 3.5, 1.5]),
        SpotLight([0.0, 3.5, 0.0], [0.0, -1.0, -0.2], 40.0),
    )
    objects = [plane("floor", size=[7, 7]), sphere("ball", [0.3, 0.9, 0.2], 0.35, subdivisions=2),
               box("block", [-0.7, 0.3, -0.4], [0.5, 0.6, 0.5]),
               box("slab", [0.9, 1.1, -0.6], [0.7, 0.08, 0.5]),
               box("wall", [0.0, 0.7, -1.6], [3.0, 1.4, 0.1])]
    return Scene(camera=Camera(eye=[0.5, 3.6, 4.2], target=[0.0, 0.4, -0.3], fov_y=48.0),
                 objects=objects, lights=lights, width=width, height=height)


def check_mask(label: str, got: np.ndarray, want: np.ndarray, near: np.ndarray) -> None:
    bad = got != want
    off = bad & ~(near | edge_pixels(got) | edge_pixels(want))
    assert not off.any(), f"{label}: {np.argwhere(off)[:5].tolist()}"
    assert bad.sum() <= max(4, MAX_MISMATCH_FRACTION * got.size), f"{label}: {bad.sum()}"


def check_definitions(frame, soft) -> None:
    """The identities of docs/CONVENTIONS.md within one renderer's frame."""
    np.testing.assert_array_equal(frame.casters.any(-1), frame.lit_count < frame.facing_count)
    np.testing.assert_array_equal(frame.facing, frame.facing_count > 0)
    np.testing.assert_array_equal(frame.lit, frame.lit_count == soft.samples[:, None, None])
    np.testing.assert_array_equal(frame.cast, frame.casters.any(-1))
    assert (frame.facing_count <= soft.samples[:, None, None]).all()
    assert not (frame.facing_count[:, ~frame.coverage]).any()


def test_area_lights_of_every_shape_and_hard_lights_agree(ctx):
    scene = every_shape_scene()
    n = len(scene.objects)
    with Renderer(scene, ctx) as r:
        raster = r.render(outputs=("lit", "coverage") + GROUND_TRUTH)
    traced = raytrace.ground_truth(scene)
    soft = raytrace.soft_masks(scene)
    assert soft.samples.tolist() == [9, 8, 6, 1, 1]
    for frame in (raster, traced):
        check_definitions(frame, soft)
    # the ray tracer's counts are soft_masks' own; its umbra and penumbra too
    np.testing.assert_array_equal(traced.lit_count, soft.lit_count)
    np.testing.assert_array_equal(traced.facing, soft.facing)
    np.testing.assert_array_equal(traced.umbra, soft.umbra)
    np.testing.assert_array_equal(traced.penumbra, soft.penumbra)
    check_counts(scene, raster, traced)
    check_facing_counts(scene, raster, traced)
    ids = np.logical_or.reduce([edge_pixels(raster.object_id == k) | edge_pixels(
        traced.object_id == k) for k in range(n + 1)])
    check_mask("object_id", raster.object_id, traced.object_id, ids)
    got_bits, want_bits = decode_casters(raster.casters, n), decode_casters(traced.casters, n)
    for i in range(len(scene.lights)):
        for name in ("facing", "cast", "umbra", "penumbra"):
            check_mask(f"light {i} {name}", getattr(raster, name)[i], getattr(traced, name)[i],
                       ids)
        for j in range(n):
            check_mask(f"light {i} casters bit {j}", got_bits[i, ..., j], want_bits[i, ..., j],
                       ids)
    # the scene tests something: every light has a penumbra or a cast shadow, the area lights
    # an umbra and pixels that only some samples face
    for i in range(len(scene.lights)):
        assert traced.cast[i].sum() > 20, i
    partial = (traced.facing_count > 0) & (traced.facing_count < soft.samples[:, None, None])
    assert all(partial[i].any() for i in range(2)) and all(traced.umbra[i].any() for i in range(3))
    assert (got_bits.sum(axis=-1) >= 2).any()   # overlapping shadows: several bits
