"""The shadow switches in the ray tracer (docs/CONVENTIONS.md, "Shadow switches"), on a scene
whose shadows overlap (`builders.overlapping_shadows`: point, directional, spot and rect area
lights):

- an object's `cast_shadows` off changes the masks, the counts and the casters exactly where
  its casters bit was set (lit where no other bit was), its own bit cleared, nothing else;
- an object's `receive_shadows` off lights its pixels by every facing sample of every light
  (no caster named there), nothing else changes;
- a light's `shadows` off makes its lit its own facing output, the other lights unchanged;
- the switched scenes against the float64 brute force (`exact`, which honours the switches
  as the definition says) within the masks' budget, the casters bit by bit off the edges;
- Whitted's image: an unreceiving object's pixels are the image with every light's shadows
  off, to float64 rounding, and nothing else changes; switching every object's casting off
  gives the same image as switching every light's shadows off; a caster switched off changes
  the image only within a pixel of where the masks changed; the ray tree's shadow verdicts
  follow the switches.
"""

from __future__ import annotations

import numpy as np
import pytest
from builders import (
    check_cast_switch,
    check_light_switch,
    check_receive_switch,
    overlapping_shadows,
    switched,
)
from exact import exact_casters

from raytrace.outlook import whitted
from raytrace.camera import primary_rays
from raytrace.groundtruth import ground_truth
from raytrace.outlook.raytree import BLOCKED, LIT, ray_tree
from shadowvol.compare.maskdiff import count_edges, edge_pixels
from shadowvol.frame import decode_casters

OUTPUTS = ("facing", "facing_count", "casters", "object_id")
SCENE = overlapping_shadows()
ROUNDING = 1e-12   # relative: float64 sums of a few terms; a shadow changes a pixel by ~0.1


@pytest.fixture(scope="module")
def before():
    return ground_truth(SCENE, OUTPUTS)


@pytest.mark.parametrize("j", [1, 2, 3])
def test_cast_switch(before, j):
    after = ground_truth(switched(SCENE, cast=[j]), OUTPUTS)
    alone = check_cast_switch(before, after, j, len(SCENE.objects))
    assert alone[before.samples == 1].any()


@pytest.mark.parametrize("k", [0, 1, 2])
def test_receive_switch(before, k):
    check_receive_switch(before, ground_truth(switched(SCENE, receive=[k]), OUTPUTS), k)


@pytest.mark.parametrize("i", range(len(SCENE.lights)))
def test_light_switch(before, i):
    check_light_switch(before, ground_truth(switched(SCENE, lights=[i]), OUTPUTS), i)


def test_numpy_backend_switches_the_same(before):
    scene = switched(SCENE, cast=[3], receive=[1], lights=[1])
    got = ground_truth(scene, OUTPUTS, backend="numpy")
    ref = ground_truth(scene, OUTPUTS)
    for name in ("lit_count", "casters"):
        differ = (getattr(got, name) != getattr(ref, name))
        differ = differ.any(-1) if name == "casters" else differ
        # float64 and float32 may differ only at edges (tests/raytrace/test_backends.py)
        edges = np.stack([count_edges(c) for c in ref.lit_count])
        assert not (differ & ~edges).any(), name


@pytest.mark.parametrize("switches", [dict(cast=[1]), dict(cast=[3], receive=[2]),
                                      dict(receive=[0], lights=[0]), dict(cast=[0, 1, 2, 3])],
                         ids=["post casts nothing", "card casts, ball receives nothing",
                              "floor receives, point light casts nothing", "nothing casts"])
def test_switched_scene_against_the_brute_force(switches):
    scene = switched(SCENE, **switches)
    got = ground_truth(scene, OUTPUTS)
    want = exact_casters(scene)
    n = len(scene.objects)
    ids = want["object_id"]
    edges = np.logical_or.reduce([edge_pixels(ids == k) | edge_pixels(got.object_id == k)
                                  for k in range(n + 1)])
    assert (got.object_id != ids).sum() <= 0.001 * ids.size
    for name in ("lit_count", "facing_count"):
        for i in range(len(scene.lights)):
            g, w = getattr(got, name)[i], want[name][i]
            bad = (g != w) & ~(edges | count_edges(g) | count_edges(w))
            assert not bad.any(), (name, i, np.argwhere(bad)[:5].tolist())
            assert (g != w).sum() <= 0.002 * g.size, (name, i)
    bits, exact = decode_casters(got.casters, n), decode_casters(want["casters"], n)
    for i in range(len(scene.lights)):
        for j in range(n):
            g, w = bits[i, ..., j], exact[i, ..., j]
            bad = (g != w) & ~(edges | edge_pixels(g) | edge_pixels(w))
            assert not bad.any(), (i, j, np.argwhere(bad)[:5].tolist())
    for j in switches.get("cast", []):
        assert not bits[..., j].any() and not exact[..., j].any()
    np.testing.assert_array_equal(got.casters.any(-1), got.lit_count < got.facing_count)


def whitted_objects(scene) -> np.ndarray:
    """(H, W) int: the object Whitted sees at each pixel centre (its own primary hits: the
    exact sphere and plane, not the masks' tessellation), -1 for none."""
    _, obj, _ = whitted.World(scene).nearest(*primary_rays(scene.camera, scene.width,
                                                           scene.height))
    return obj.reshape(scene.height, scene.width)


def test_whitted_receive_switch():
    shadowless = whitted.render(switched(SCENE, lights=range(len(SCENE.lights))), max_depth=0)
    plain = whitted.render(SCENE, max_depth=0)
    seen = whitted_objects(SCENE)
    for k in (0, 1, 2):
        image = whitted.render(switched(SCENE, receive=[k]), max_depth=0)
        own = seen == k
        # equal up to float64 rounding (BLAS sums subsets of different lengths its own way)
        np.testing.assert_allclose(image[own], shadowless[own], rtol=ROUNDING, atol=0)
        np.testing.assert_allclose(image[~own], plain[~own], rtol=ROUNDING, atol=0)
        assert (image[own] != plain[own]).any()   # its shadows are gone


def test_whitted_casters_and_lights_switched_off_agree():
    no_casters = whitted.render(switched(SCENE, cast=range(len(SCENE.objects))), max_depth=0)
    no_shadows = whitted.render(switched(SCENE, lights=range(len(SCENE.lights))), max_depth=0)
    np.testing.assert_allclose(no_casters, no_shadows, rtol=ROUNDING, atol=0)
    assert (no_shadows != whitted.render(SCENE, max_depth=0)).any()


def test_whitted_cast_switch_changes_the_image_where_the_masks_change(before):
    after = ground_truth(switched(SCENE, cast=[3]), OUTPUTS)
    masks_changed = (after.lit_count != before.lit_count).any(0)
    plain = whitted.render(SCENE, max_depth=0)
    image = whitted.render(switched(SCENE, cast=[3]), max_depth=0)
    changed = ~np.isclose(image, plain, rtol=ROUNDING, atol=0).all(-1)
    # Whitted's shadow rays keep their own offset (raytrace.tolerances): edges may move a pixel
    near = edge_pixels(masks_changed) | masks_changed
    assert not (changed & ~near).any()
    assert (changed & masks_changed).sum() >= 0.9 * masks_changed.sum() > 0


def test_the_ray_tree_gives_whitted_s_verdict_under_the_switches(before):
    """A pixel deep in one hard light's shadow of one object alone: the ray tree's shadow ray
    to that light is blocked, and lit once that object casts nothing, the object seen there
    receives nothing, or the light casts nothing."""
    n = len(SCENE.objects)
    for i, j in ((i, j) for i in range(3) for j in range(n)):
        bits = decode_casters(before.casters[i], n)
        alone = bits[..., j] & ~np.delete(bits, j, axis=-1).any(-1)
        deep = alone & ~edge_pixels(alone) & ~np.logical_or.reduce(
            [edge_pixels(before.object_id == k) for k in range(n + 1)])
        if deep.any():
            break
    y, x = np.argwhere(deep)[len(np.argwhere(deep)) // 2]
    seen = int(before.object_id[y, x]) - 1

    hard = SCENE.replace(lights=SCENE.lights[:3])   # the ray tree draws hard lights only

    def verdict(scene):
        return ray_tree(scene, int(x), int(y), max_depth=0).children[i].verdict

    assert verdict(hard) == BLOCKED
    for switches in (dict(cast=[j]), dict(receive=[seen]), dict(lights=[i])):
        assert verdict(switched(hard, **switches)) == LIT, switches
