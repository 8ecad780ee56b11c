"""`casters` past one 64-bit word, and for area lights: a grid of 210 small boxes of two
heights on a floor (211 objects, K = 4 words) under a point light and a rect area light.  Both
renderers' casters equal, bit for bit, the objects a float64 brute-force walk of each shadow
segment meets (tests/exact.py `exact_casters`) at every pixel off an edge (one pixel) of the
object ids or of that object's bit in either; and `casters.any(-1) == (lit_count <
facing_count)` exactly in both."""

from __future__ import annotations

import numpy as np
import pytest
from exact import exact_casters

import raytrace
from shadowvol.compare.maskdiff import edge_pixels
from shadowvol.frame import caster_words, decode_casters
from shadowvol.primitives import box, plane
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import AreaLight, Camera, PointLight, Scene

pytestmark = pytest.mark.gl

GRID = (15, 14)   # 210 boxes


def grid_scene(light) -> Scene:
    """The floor (object 0) and GRID boxes, every other one twice as tall, so that the tall
    ones shade their short neighbours as well as the floor."""
    boxes = []
    for k in range(GRID[0] * GRID[1]):
        x, z = k % GRID[0], k // GRID[0]
        tall = 0.5 if (x + z) % 2 else 0.25
        boxes.append(box(f"b{k}", [0.32 * x - 2.24, tall / 2, 0.32 * z - 2.08],
                         [0.16, tall, 0.16]))
    return Scene(camera=Camera(eye=[0.0, 5.5, 3.2], target=[0.0, 0.0, -0.1], fov_y=50.0),
                 objects=[plane("floor", size=[6, 6])] + boxes, lights=[light],
                 width=96, height=72)


LIGHTS = {
    "point": PointLight([0.7, 3.0, 0.9]),
    "rect": AreaLight(shape="rect", center=[0.5, 3.0, 0.6], normal=[0.0, -1.0, 0.0],
                      size=(0.6, 0.6), samples=4, seed=3),
}


def check_against_exact(frame, want: dict, objects: int) -> int:
    """Every bit equal off the edges; returns how many (pixel, object) bits are set."""
    ids = want["object_id"]
    assert (frame.object_id != ids).sum() <= 0.01 * ids.size
    id_edges = np.logical_or.reduce([edge_pixels(ids == k) | edge_pixels(frame.object_id == k)
                                     for k in np.unique(np.concatenate(
                                         [ids.ravel(), frame.object_id.ravel()]))])
    got, exact = decode_casters(frame.casters, objects), decode_casters(want["casters"], objects)
    for i in range(len(frame.casters)):
        for j in np.flatnonzero(got[i].any(axis=(0, 1)) | exact[i].any(axis=(0, 1))):
            g, w = got[i, ..., j], exact[i, ..., j]
            bad = (g != w) & ~(id_edges | edge_pixels(g) | edge_pixels(w))
            assert not bad.any(), f"light {i}, object {j}: {np.argwhere(bad)[:5].tolist()}"
    np.testing.assert_array_equal(frame.casters.any(-1), frame.lit_count < frame.facing_count)
    return int(exact.sum())


@pytest.mark.parametrize("kind", list(LIGHTS))
def test_210_boxes_casters_equal_a_float64_walk_in_both_renderers(ctx, kind):
    scene = grid_scene(LIGHTS[kind])
    n = len(scene.objects)
    assert n == 211 and caster_words(n) == 4
    want = exact_casters(scene)
    with Renderer(scene, ctx) as r:
        raster = r.render(outputs=("lit", "coverage", "object_id", "facing_count", "casters"))
    traced = raytrace.ground_truth(scene, outputs=("object_id", "facing_count", "casters"))
    for frame in (raster, traced):
        assert frame.casters.shape == (1, 72, 96, 4) and frame.casters.dtype == np.uint64
        assert check_against_exact(frame, want, n) > 500
    # the walk finds casters in every word, the last (objects 192 ..) included
    assert all(want["casters"][..., k].any() for k in range(4))
    # the two renderers' bits, word by word, off the edges of either
    same = (raster.casters == traced.casters).all(-1)
    assert same.mean() > 0.97


def test_the_documented_numpy_decoding_line():
    """`np.unpackbits(casters.view(np.uint8), axis=-1, bitorder="little")[..., :n]` is the
    bit j mod 64 of word j div 64 of every pixel (docs/CONVENTIONS.md)."""
    rng = np.random.default_rng(5)
    n = 150
    casters = rng.integers(0, 2**63, size=(2, 3, 4, caster_words(n)), dtype=np.uint64)
    casters[..., -1] &= np.uint64((1 << (n - 128)) - 1)   # no bit past the last object
    decoded = np.unpackbits(casters.view(np.uint8), axis=-1, bitorder="little")[..., :n]
    assert decoded.shape == (2, 3, 4, n)
    for j in (0, 1, 63, 64, 100, 127, 128, 149):
        bit = (casters[..., j // 64] >> np.uint64(j % 64)) & np.uint64(1)
        np.testing.assert_array_equal(decoded[..., j], bit)
    np.testing.assert_array_equal(decode_casters(casters, n), decoded.astype(bool))
