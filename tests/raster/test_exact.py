"""Tiny exact GL tests: known quads, exact stencil counts after the volume passes.

The 4x4 scene: the camera at z = 5 looks down -z; pixel centres sit at x, y = +-0.05 d and
+-0.15 d at distance d.  A directional light travels along (1, 0, -1).  Occluder A (z = -4,
x in [-2, -0.9]) is seen in column 0 and shadows column 1 of the backdrop (z = -5); occluder B
(z = -3, x in [-3, -1.9]) is seen by no pixel but shadows column 0 (A) and column 1 again.
So every row of the stencil must read [1, 2, 0, 0].
"""

from __future__ import annotations

import numpy as np
import pytest
from builders import tiny_scene

from shadowvol.primitives import plane, sphere
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import Camera, DirectionalLight, Material, PointLight, Scene

METHODS = ("zpass", "zfail", "auto")
SILHOUETTES = ("cpu", "gpu")


@pytest.mark.parametrize("silhouettes", SILHOUETTES)
@pytest.mark.parametrize("method", METHODS)
def test_stencil_counts_4x4(ctx, method, silhouettes):
    with Renderer(tiny_scene(), ctx) as r:
        res = r.render(method, silhouettes, stencil=True)
    assert res.stencil.shape == (1, 4, 4)
    np.testing.assert_array_equal(res.stencil[0], np.tile([1, 2, 0, 0], (4, 1)))
    np.testing.assert_array_equal(res.lit[0], np.tile([False, False, True, True], (4, 1)))
    assert res.coverage.all()


@pytest.mark.parametrize("silhouettes", SILHOUETTES)
def test_eye_inside_a_volume_4x4(ctx, silhouettes):
    """Z-pass counts from the eye: with the eye inside the roof's volume every count is one
    short.  Z-fail counts from infinity and is exact; auto picks z-fail for the roof."""
    with Renderer(tiny_scene(with_blocker_behind_eye=True), ctx) as r:
        zpass = r.render("zpass", silhouettes, stencil=True)
        zfail = r.render("zfail", silhouettes, stencil=True)
        auto = r.render("auto", silhouettes, stencil=True)
    np.testing.assert_array_equal(zpass.stencil[0], np.tile([0, 1, -1, -1], (4, 1)))
    np.testing.assert_array_equal(zfail.stencil[0], np.tile([1, 2, 0, 0], (4, 1)))
    np.testing.assert_array_equal(auto.stencil[0], np.tile([1, 2, 0, 0], (4, 1)))
    assert auto.zfail[0].tolist() == [False, False, False, True]


def test_auto_uses_zpass_when_the_near_plane_cuts_nothing(ctx):
    with Renderer(tiny_scene(), ctx) as r:
        assert not r.render("auto").zfail.any()


# ---- caps never shadow the lit surface they lie on (exact depth ties, see volumes.py) -------

LIT_CASES = {
    "floor": dict(objects=[plane("floor", size=[10, 10])],
                  light=PointLight([1.0, 3.0, 1.0])),
    # one open, single quad, tilted, seen from the side the light is on
    "open quad": dict(objects=[plane("quad", point=[0, 0.5, 0], normal=[0.3, 1, 0.4],
                                     size=[3, 2])],
                      light=PointLight([-1.0, 4.0, 2.0])),
    # the same quad wound the other way: the winding must not matter
    "open quad flipped": dict(objects=[plane("quad", point=[0, 0.5, 0], normal=[-0.3, -1, -0.4],
                                             size=[3, 2])],
                              light=PointLight([-1.0, 4.0, 2.0])),
    "directional floor": dict(objects=[plane("floor", size=[10, 10])],
                              light=DirectionalLight([0.3, -1.0, 0.2])),
}


@pytest.mark.parametrize("silhouettes", SILHOUETTES)
@pytest.mark.parametrize("case", sorted(LIT_CASES))
def test_zfail_caps_leave_lit_surfaces_at_zero(ctx, case, silhouettes):
    spec = LIT_CASES[case]
    scene = Scene(camera=Camera(eye=[0.5, 2.5, 5.0], target=[0, 0, 0]), objects=spec["objects"],
                  lights=[spec["light"]], width=96, height=72)
    with Renderer(scene, ctx) as r:
        res = r.render("zfail", silhouettes, stencil=True)
    assert res.coverage.sum() > 1000
    # every covered pixel: count exactly 0, and lit (the light is on the visible side)
    assert (res.stencil[0][res.coverage] == 0).all(), np.unique(res.stencil[0][res.coverage])
    np.testing.assert_array_equal(res.lit[0], res.coverage)


@pytest.mark.parametrize("silhouettes", SILHOUETTES)
def test_zfail_caps_on_a_closed_mesh(ctx, silhouettes):
    """A lone sphere: the lit side counts 0 (its near caps tie with it), the dark side counts
    the light-facing triangles in front of it.  Which side is which comes from the ray tracer:
    a lone convex mesh never shadows its own lit side, so its lit mask IS the lit side."""
    from scipy.ndimage import binary_erosion

    import raytrace

    ball = sphere("ball", [0, 0, 0], 1.0, subdivisions=2)
    scene = Scene(camera=Camera(eye=[0.0, 0.5, 4.0], target=[0, 0, 0]), objects=[ball],
                  lights=[PointLight([2.0, 3.0, 1.0])], width=64, height=48)
    ref_lit, ref_cov = raytrace.shadow_masks(scene)
    with Renderer(scene, ctx) as r:
        res = r.render("zfail", silhouettes, stencil=True)
    # the terminator and the outline are left out by eroding each region by one pixel
    lit_side = binary_erosion(ref_lit[0])
    dark_side = binary_erosion(ref_cov & ~ref_lit[0])
    assert lit_side.sum() > 200 and dark_side.sum() > 100
    assert (res.stencil[0][lit_side] == 0).all()
    assert (res.stencil[0][dark_side] > 0).all()
    assert res.lit[0][lit_side].all()
    assert not res.lit[0][dark_side].any()


def test_renderer_reuses_one_context_and_releases(ctx):
    """Many frames on one context, camera moved between them, then everything released."""
    scene = tiny_scene()
    camera = Camera(eye=[-0.5, 0, 5], target=[-0.5, 0, 0], fov_y=scene.camera.fov_y)
    with Renderer(scene, ctx) as r:
        first = r.render()
        moved = r.render(camera=camera)
        again = r.render()
    with Renderer(scene.replace(camera=camera), ctx) as fresh:
        expect_moved = fresh.render()
    np.testing.assert_array_equal(first.lit, again.lit)
    np.testing.assert_array_equal(moved.lit, expect_moved.lit)
    np.testing.assert_array_equal(moved.lit[0], np.tile([False, False, False, True], (4, 1)))
    assert r.ctx is None  # released; the shared context itself stays usable
    assert ctx.error == "GL_NO_ERROR"


def test_shading_matches_the_phong_formula(ctx):
    """One lit pixel of the backdrop, by hand: ka * ambient + kd (n . l) + ks (r . v)^s."""
    mat = Material(ambient=[0.2, 0.1, 0.0], diffuse=[0.5, 0.6, 0.7], specular=[0.3, 0.3, 0.3],
                   shininess=4)
    light = PointLight([0.0, 0.0, 3.0], color=[1.0, 0.8, 0.6], intensity=0.5)
    scene = Scene(camera=Camera(eye=[0, 0, 5], target=[0, 0, 0]),
                  objects=[plane("wall", point=[0, 0, -1], normal=[0, 0, 1], size=[20, 20],
                                 material=mat)],
                  lights=[light], width=5, height=5, ambient=[1.0, 1.0, 1.0])
    with Renderer(scene, ctx) as r:
        res = r.render()
    # the centre pixel looks straight down -z at (0, 0, -1): the light is straight above it
    n, l = np.array([0, 0, 1.0]), np.array([0, 0, 1.0])
    v = np.array([0, 0, 1.0])
    r_ = 2 * (n @ l) * n - l
    expect = mat.ambient + (mat.diffuse * (n @ l) + mat.specular * (r_ @ v) ** 4) * light.radiance
    np.testing.assert_allclose(res.image[2, 2], expect, rtol=1e-5)
