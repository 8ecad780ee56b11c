"""The shadow switches in the rasterizer (docs/CONVENTIONS.md, "Shadow switches"), auto and
z-fail, CPU and GPU silhouettes, on `builders.overlapping_shadows` (point, directional, spot
and rect area lights):

- the raster's own frames obey the switches exactly (`builders.check_cast_switch`,
  `check_receive_switch`, `check_light_switch`: the masks, counts and casters change exactly
  where the switched object's bit, object or light says, nothing else), and the image changes
  exactly at the pixels whose counts changed;
- raster = ray tracer on the switched scenes under the usual budgets (`assert_masks_match`
  for lit and coverage, `builders.check_counts` for the counts, every casters bit off the
  edges);
- a mask-only frame (no G-buffer: the switches in the mask pass, with the bits in the
  stencil and in a colour target) gives the deferred frame's masks bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest
from builders import (
    check_cast_switch,
    check_counts,
    check_light_switch,
    check_receive_switch,
    overlapping_shadows,
    switched,
)

from raytrace.groundtruth import ground_truth
from shadowvol.compare.maskdiff import edge_pixels
from shadowvol.frame import decode_casters
from shadowvol.primitives import mesh, plane
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import Camera, PointLight, Scene

pytestmark = pytest.mark.gl

OUTPUTS = ("image", "lit", "coverage", "facing", "facing_count", "casters", "object_id")
SCENE = overlapping_shadows()
WAYS = [("auto", "cpu"), ("zfail", "cpu"), ("auto", "gpu"), ("zfail", "gpu")]
SWITCHES = {"post casts nothing": dict(cast=[1]), "card casts nothing": dict(cast=[3]),
            "floor receives nothing": dict(receive=[0]),
            "post receives nothing": dict(receive=[1]),
            "point light casts nothing": dict(lights=[0]),
            "area light casts nothing": dict(lights=[3]),
            "all at once": dict(cast=[3], receive=[2], lights=[1])}


def frames(scene, ctx) -> dict[tuple[str, str], object]:
    with Renderer(scene, ctx) as r:
        return {(m, s): r.render(m, s, outputs=OUTPUTS) for m, s in WAYS}


@pytest.fixture(scope="module")
def before(gl_session):
    return frames(SCENE, gl_session)


def check_image(before, after) -> None:
    """The image changes exactly where some light's count changed."""
    counts = (after.lit_count != before.lit_count).any(0)
    np.testing.assert_array_equal((after.image != before.image).any(-1), counts)


@pytest.mark.parametrize("name", SWITCHES)
def test_switches_in_the_rasterizer(ctx, before, assert_masks_match, name):
    switches = SWITCHES[name]
    scene = switched(SCENE, **switches)
    ref = ground_truth(scene, OUTPUTS[3:])
    n = len(scene.objects)
    for way, after in frames(scene, ctx).items():
        label = f"{name}, {way}"
        if list(switches) == ["cast"]:
            check_cast_switch(before[way], after, switches["cast"][0], n)
        elif list(switches) == ["receive"]:
            check_receive_switch(before[way], after, switches["receive"][0])
        elif list(switches) == ["lights"]:
            check_light_switch(before[way], after, switches["lights"][0])
        check_image(before[way], after)
        # raster = ray tracer on the switched scene
        assert_masks_match(after, ref.lit, ref.coverage, label)
        check_counts(scene, after, ref)
        got, want = decode_casters(after.casters, n), decode_casters(ref.casters, n)
        ids = np.logical_or.reduce([edge_pixels(after.object_id == k) |
                                    edge_pixels(ref.object_id == k) for k in range(n + 1)])
        for i in range(len(scene.lights)):
            for j in range(n):
                g, w = got[i, ..., j], want[i, ..., j]
                bad = (g != w) & ~(ids | edge_pixels(g) | edge_pixels(w))
                assert not bad.any(), (label, i, j, np.argwhere(bad)[:4].tolist())
        for j in switches.get("cast", []):
            assert not got[..., j].any(), label
        np.testing.assert_array_equal(after.casters.any(-1),
                                      after.lit_count < after.facing_count)


@pytest.mark.parametrize("name", ["card casts nothing", "post receives nothing",
                                  "all at once"])
def test_mask_only_frames_switch_the_same(ctx, name):
    # hard lights alone (the area light's samples would not fit the stencil's layout)
    scene = switched(SCENE.replace(lights=SCENE.lights[:3]), **SWITCHES[name])
    with Renderer(scene, ctx) as r:
        for method, silhouettes in WAYS:
            full = r.render(method, silhouettes, outputs=OUTPUTS)
            for in_stencil in (True, False):
                r.masks_in_stencil = in_stencil
                masks = r.render(method, silhouettes, outputs=("lit", "coverage"))
                np.testing.assert_array_equal(masks.lit, full.lit)
                np.testing.assert_array_equal(masks.coverage, full.coverage)
            r.masks_in_stencil = True
        assert (full.lit != r.render(shadows=False, outputs=("lit",)).lit).any()


def test_objects_that_cast_nothing_count_nothing(ctx, monkeypatch, assert_masks_match):
    """256 stacked sheets (one mesh) over a floor would wrap the stencil; switched off they
    add nothing to the counts' bound (`Renderer.count_bound`), so the overflow check never
    runs, and the floor under them is lit as the ray tracer says, by both methods."""
    from shadowvol.raster.overflow import detect

    def must_not_run(*args, **kwargs):
        raise AssertionError("the overflow check ran")

    corners = np.array([[-0.5, 0, -0.5], [0.5, 0, -0.5], [0.5, 0, 0.5], [-0.5, 0, 0.5]])
    z = np.linspace(1.0, 2.0, 256)
    v = corners[None] + np.stack([np.zeros_like(z), z, np.zeros_like(z)], 1)[:, None]
    f = np.array([[0, 1, 2], [0, 2, 3]])[None] + 4 * np.arange(256)[:, None, None]
    scene = Scene(camera=Camera(eye=[0, 0.8, 3.0], target=[0, 0, 0], fov_y=60),
                  objects=[plane("floor", size=[6, 6]),
                           mesh("sheets", v.reshape(-1, 3), f.reshape(-1, 3))],
                  lights=[PointLight([0.1, 4.0, 0.05])], width=64, height=48)
    scene = switched(scene, cast=[1])
    ref = ground_truth(scene, ("object_id",))
    assert (ref.lit[0] & (ref.object_id == 1)).sum() > 100   # the floor under them is lit
    monkeypatch.setattr(detect, "find_wrapped", must_not_run)
    with Renderer(scene, ctx) as r:
        assert r.count_bound == 2
        for method in ("auto", "zfail"):
            assert_masks_match(r.render(method), ref.lit, ref.coverage, method)
