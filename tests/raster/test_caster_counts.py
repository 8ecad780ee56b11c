"""The per-caster counts behind `casters` (shadowvol.raster.truth.truth_pass.CasterCounts),
exactly: each caster's counter after the one counting pass (z-fail under the complementary depth
test) equals that caster's own stencil count (its volumes alone through the stencil pass) at every
pixel, negative counts too (z-pass forced where the near plane cuts a volume), the counters
sum to the frame's stencil count, and the stencil the counting pass leaves marks every pixel
where a counter is not 0.  On every scene file with hard lights and on built cases, z-pass,
z-fail and auto, CPU and GPU silhouettes."""

from __future__ import annotations

import numpy as np
import pytest
from builders import SCENES, cards_scene
from worlds import lamp_room

from shadowvol.primitives import box, plane, sphere
from shadowvol.raster import passes
from shadowvol.raster.truth import truth_pass
from shadowvol.raster.renderer import Renderer
from shadowvol.raster.stencil import zero_to_one_depth
from shadowvol.scene import (
    AreaLight,
    Camera,
    DirectionalLight,
    PointLight,
    Scene,
    SpotLight,
)
from shadowvol.scenefile import load_scene

SIZE = dict(width=96, height=72)


def scene_cases() -> dict[str, Scene]:
    out = {}
    for path in sorted(SCENES.glob("*.toml")):
        scene = load_scene(path).replace(**SIZE)
        if scene.lights and not any(isinstance(lt, AreaLight) for lt in scene.lights):
            out[path.stem] = scene
    spot = SpotLight([0.5, 4.0, 1.5], [-0.1, -1.0, -0.3], 35.0)
    balls = [sphere(f"ball{i}", [x, 0.5 + 0.3 * i, z], 0.35, subdivisions=2)
             for i, (x, z) in enumerate([(-1.2, 0.0), (-0.4, 0.3), (0.4, -0.2), (1.1, 0.4)])]
    # open cards (soups: counts above 2), a wall, and the eye inside a ball's shadow so that
    # auto mixes z-pass and z-fail
    out["balls, cards and a wall"] = Scene(
        camera=Camera(eye=[0.3, 0.45, 2.2], target=[-0.2, 0.5, 0.0], fov_y=60.0),
        objects=[plane("floor", size=[8, 8])] + balls
        + [box("wall", [0.0, 1.0, -1.5], [4.0, 2.0, 0.1]),
           sphere("over the eye", [0.3, 1.5, 2.0], 0.3, subdivisions=1)]
        + list(cards_scene(**SIZE).objects[1:]),
        lights=[PointLight([0.3, 4.0, 2.0]), DirectionalLight([-0.6, -1.0, -0.3]), spot],
        **SIZE)
    # a ground quad 1e7 wide: cut into pieces near the eye, its far cap cut too (large worlds)
    out["huge ground"] = lamp_room(1e7, offset=[2e6, 0.0, -1e6], turn=30.0,
                                   size=(SIZE["width"], SIZE["height"])).replace(
        camera=Camera(eye=[3.0, 2.5, 4.0], target=[-1.0, 0.2, -0.5], fov_y=60.0))
    return out


CASES = scene_cases()


@pytest.mark.parametrize("name", list(CASES))
@pytest.mark.parametrize("method, silhouettes", [("auto", "cpu"), ("zfail", "cpu"),
                                                 ("auto", "gpu"), ("zpass", "cpu")])
def test_per_caster_counts_are_each_casters_stencil_count(ctx, gl_session, name, method,
                                                          silhouettes):
    scene = CASES[name]
    n = len(scene.objects)
    assert n <= truth_pass.CASTERS_PER_GROUP
    objects = list(range(n))
    with Renderer(scene, gl_session) as r:
        frame = r.render(method, silhouettes, stencil=True,
                         outputs=("lit", "coverage", "casters"))
        covered = frame.coverage
        vols = r.volumes(silhouettes)
        counter = r._truth_pass().casters
        layout = truth_pass.counter_layout(r.object_bounds[objects])
        whole = (0, 0, scene.width, scene.height)
        checked = negative = 0
        for i, light in enumerate(scene.lights):
            # the frame's depth buffer is still there, read with the frame's depth range; the
            # volumes of this light
            zfail = frame.zfail[i]
            vols.prepare(light.homogeneous)
            with zero_to_one_depth(r.gl):
                pipe = r.pipeline.with_volumes(vols)
                counter.count(pipe, zfail, objects, layout, halve=False, clip_planes=None,
                              box=whole)
                together = r.target.read_stencil()
                counts = counter.read_counts(layout)
                alone = []
                for j in objects:
                    passes.count_signed(pipe, zfail, objects=[j])
                    alone.append(r.target.read_stencil())
            assert counts.min() >= -128 and counts.max() < 128   # the int8 stencil's range
            for j in objects:
                np.testing.assert_array_equal(counts[j], alone[j],
                                              err_msg=f"light {i}, object {j}")
            np.testing.assert_array_equal(counts.sum(axis=0), frame.stencil[i],
                                          err_msg=f"light {i}: the counters' sum")
            touched = (counts != 0).any(axis=0)
            assert (together[touched] == 1).all() and set(np.unique(together)) <= {0, 1}
            checked += int(touched[covered].sum())
            negative += int((counts < 0).any(axis=0)[covered].sum())
        assert checked > 0   # some pixel is in some caster's volume
        if (name, method) == ("inside_shadow", "zpass"):
            assert negative > 0   # the forced z-pass's wrong counts are read exactly too


def test_counter_layout_packs_by_width():
    # bounds: convex (2), a soup of 300 triangles, one of 70,000
    layout = truth_pass.counter_layout(np.array([2, 300, 2, 70_000, 2, 2, 2]))
    assert layout == [(0, 0, 8), (2, 0, 16), (0, 8, 8), (3, 0, 32), (0, 16, 8), (0, 24, 8),
                      (1, 0, 8)]
    # a biased field of w bits holds counts below 2^(w - 1)
    assert truth_pass.counter_layout(np.array([127, 128, 32_767, 32_768])) == [
        (0, 0, 8), (1, 0, 16), (1, 16, 16), (2, 0, 32)]
