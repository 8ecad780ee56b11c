"""The eye exactly on the plane of a shadow volume's side face (issue 31).

With the eye on the line from a point light through a corner of an open card (so on the plane of
both side quads that meet there), z-fail drew those side triangles with depth clamp on: never
clipped at the near plane, each was rasterized through w = 0, where float32 rounding of its
corners decided which half of the view it covered: thousands of floor pixels counted shadowed,
by the CPU silhouettes on this machine (llvmpipe, 256-bit) and by the GPU ones on others.  Side
quads are now clipped at the near plane (`stencil.zfail_counting`).  Every run (auto, z-fail;
CPU, GPU silhouettes) must match the ray tracer with the mask budget, and the GPU silhouettes
must give the CPU ones' masks: both draw the same side triangles, the same corners in the same
order (silhouette.geom), even at the ties along the side plane's edge-on image.
"""

from __future__ import annotations

import numpy as np
import pytest

import raytrace
from shadowvol.primitives import box, mesh, plane
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import Camera, DirectionalLight, PointLight, Scene

RUNS = [("auto", "cpu"), ("auto", "gpu"), ("zfail", "cpu"), ("zfail", "gpu")]
# an open card (two triangles) tilted over the floor, as a random scene had it
CARD = np.array([[0.43676195566136206, 1.2377711224889618, -1.2081144964303325],
                 [1.063238044338638, 0.6468008182349883, -1.1263699463690005],
                 [1.063238044338638, 0.7622288775110382, -0.29188550356966747],
                 [0.43676195566136206, 1.3531991817650117, -0.37363005363099955]])
LIGHT = np.array([-1.25, 3.25, -1.75])


def _card_scene(corner: int, beyond: float, target) -> Scene:
    """The card under LIGHT, the eye on the line from the light through card corner `corner`,
    `beyond` times the light's distance past it (on both side planes that meet there)."""
    a = CARD[corner]
    eye = a + beyond * (a - LIGHT)
    return Scene(camera=Camera(eye=eye, target=target, fov_y=60.0, near=0.05),
                 objects=[plane("floor", size=[20, 20]),
                          mesh("card", CARD, np.array([[0, 1, 2], [0, 2, 3]]))],
                 lights=[PointLight(LIGHT)], width=96, height=72)


def _box_scene(light, eye, target) -> Scene:
    """A 1 m box on the floor; dyadic coordinates, so the eye lies exactly on the side plane
    in float32 too."""
    return Scene(camera=Camera(eye=eye, target=target, fov_y=60.0, near=0.05),
                 objects=[plane("floor", size=[16, 16]), box("box", [0.0, 1.0, 0.0], [1, 1, 1])],
                 lights=[light], width=96, height=72)


CASES = {
    "card corner, half beyond": _card_scene(3, 0.5, [1.75, 0.0, 0.5]),
    "card corner, a quarter beyond": _card_scene(3, 0.25, [1.75, 0.0, 0.5]),
    "card corner 0": _card_scene(0, 0.5, [0.5, 0.0, 1.5]),
    # the box's top edge x = 0.5, y = 1.5 and the light (0, 4, 0): the plane 5x + y = 4
    "box side plane, on the side quad": _box_scene(PointLight([0.0, 4.0, 0.0]),
                                                   [0.75, 0.25, 0.0], [2.75, 0.0, -1.0]),
    "box side plane, beyond the light": _box_scene(PointLight([0.0, 4.0, 0.0]),
                                                   [-0.25, 5.25, 0.0], [1.0, 0.0, 1.0]),
    "box, sun, on the extruded corner": _box_scene(DirectionalLight([1.0, -2.0, 0.5]),
                                                   [1.0, 0.5, 0.75], [2.0, 0.0, 1.5]),
}


@pytest.mark.gl
@pytest.mark.parametrize("name", sorted(CASES))
def test_eye_on_a_side_plane(ctx, assert_masks_match, name):
    scene = CASES[name]
    ref_lit, ref_cov = raytrace.shadow_masks(scene)
    with Renderer(scene, ctx) as r:
        results = {run: r.render(*run) for run in RUNS}
    for (method, silhouettes), res in results.items():
        assert_masks_match(res, ref_lit, ref_cov, f"{name}-{method}-{silhouettes}")
    np.testing.assert_array_equal(results["auto", "cpu"].lit, results["auto", "gpu"].lit)
    np.testing.assert_array_equal(results["zfail", "cpu"].lit, results["zfail", "gpu"].lit)
