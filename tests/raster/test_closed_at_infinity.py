"""Z-fail's volumes closed at infinity, bit for bit (issue 31, z-fail's one-sample miscounts).

A z-fail count runs from the surface to infinity, so it is exact only if each volume is closed
there too: every side quad's edge at infinity must be the far caps' edge, the same float32
direction.  The far caps (far_cap.vert, caps.vert) and the GPU sides (silhouette.geom) extrude
a frame vertex V as V * L.w - L.xyz in float32; the CPU sides were extruded in float64 world
space and rounded (V - L, 0): a different float32 direction for most edges, and so a sliver at
infinity between side and cap where a pixel's count was off by one (one sample of an area
light at one interior pixel, under z-fail only).  Checked on the buffer the CPU path uploads,
for point and directional lights, at the origin and 1e4 away, a light 1e-3 from a corner too.
"""

from __future__ import annotations

import numpy as np
import pytest

from shadowvol.primitives import box, plane, sphere
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import AreaLight, Camera, DirectionalLight, PointLight, Scene


def _scene(offset: float, light) -> Scene:
    o = np.array([offset, 0.0, -0.7 * offset])
    return Scene(camera=Camera(eye=o + [2.3, 2.1, -1.7], target=o + [-1.2, 0.0, 0.9]),
                 objects=[plane("floor", point=o, size=[12, 12]),
                          box("box", o + [0.0, 0.5, 0.0], [1, 1, 1]),
                          sphere("ball", o + [1.2, 0.7, 0.4], 0.4, subdivisions=2)],
                 lights=[light(o)], width=32, height=24)


LIGHTS = {
    "point": lambda o: PointLight(o + [0.7, 3.1, 0.3]),
    "point 1e-3 from a corner": lambda o: PointLight(o + [0.501, 1.001, 0.499]),
    "sun": lambda o: DirectionalLight([-0.3, -1.0, 0.2]),
}


@pytest.mark.gl
@pytest.mark.parametrize("offset", [0.0, 1e4])
@pytest.mark.parametrize("light", sorted(LIGHTS))
def test_cpu_sides_meet_the_far_caps_at_infinity(ctx, light, offset):
    scene = _scene(offset, LIGHTS[light])
    with Renderer(scene, ctx) as r:
        r.render("zfail", "cpu")
        vols = r.volumes("cpu")
        light4 = scene.lights[0].homogeneous
        vols.prepare(light4)
        drawn = np.frombuffer(vols._current.buffer.read(), np.float32).reshape(-1, 4)
        drawn = drawn[:len(vols._current.corners)].reshape(-1, 3, 4)
        origin = r.geometry.origin
    # the finite corner each extruded one came from: quads (e, s, s_inf, e_inf) were drawn as
    # triangles (e, s, s_inf), (e, s_inf, e_inf)
    first, second = drawn[0::2], drawn[1::2]
    assert (first[:, :2, 3] == 1).all() and (first[:, 2, 3] == 0).all()
    e, s = first[:, 0, :3], first[:, 1, :3]
    light32 = (light4[:3] - light4[3] * origin).astype(np.float32)
    w = np.float32(light4[3])
    for got, source in ((first[:, 2, :3], s), (second[:, 1, :3], s), (second[:, 2, :3], e)):
        want = source * w - light32                  # far_cap.vert's V * L.w - L.xyz
        mismatched = (got != want).any(axis=1)
        assert not mismatched.any(), (int(mismatched.sum()), len(got))


@pytest.mark.gl
@pytest.mark.parametrize("eye, target", [([2.0, 3.0, -2.0], [-1.0, 0.0, 1.0]),
                                         ([2.3, 2.1, -1.7], [-1.2, 0.0, 0.9])])
def test_zfail_sees_no_slivers_at_infinity(ctx, eye, target):
    """A point light 1e-4 from a box's corner, the camera looking along the light's rays
    past it, so the far caps' edges at infinity cross the view: the slivers (the float32
    directions of corners 1e-4 from the light are far apart) made the CPU silhouettes' z-fail
    masks differ from the GPU ones' and from auto's (z-pass here) at 9 and 12 pixels, 5 and 12
    more against the ray tracer.  They must now be the same."""
    scene = Scene(camera=Camera(eye=eye, target=target, fov_y=60.0, near=0.05),
                  objects=[plane("floor", size=[40, 40]), box("box", [0.0, 0.5, 0.0], [1, 1, 1])],
                  lights=[PointLight([0.5001, 1.0001, 0.4999])], width=256, height=192)
    with Renderer(scene, ctx) as r:
        res = {run: r.render(*run) for run in [("auto", "cpu"), ("zfail", "cpu"), ("zfail", "gpu")]}
    assert not res["auto", "cpu"].zfail.any()
    np.testing.assert_array_equal(res["zfail", "cpu"].lit, res["zfail", "gpu"].lit)
    np.testing.assert_array_equal(res["zfail", "cpu"].lit, res["auto", "cpu"].lit)


@pytest.mark.gl
@pytest.mark.parametrize("eye, target", [([2.0, 3.0, -2.0], [-1.0, 0.0, 1.0]),
                                         ([2.3, 2.1, -1.7], [-1.2, 0.0, 0.9])])
def test_zfail_counts_every_sample_of_a_light_by_a_corner(ctx, eye, target):
    """The same for an area light: eight samples of a sphere light 2e-4 from the box's corner.
    Z-fail's lit_count with CPU silhouettes was off auto's (z-pass here: no caps) at 13 and 7
    pixels, a sample each; the GPU silhouettes' at 1 and 2 edge pixels, where auto's own CPU
    side quads were the float64-extruded ones.  Now all three are equal."""
    scene = Scene(camera=Camera(eye=eye, target=target, fov_y=60.0, near=0.05),
                  objects=[plane("floor", size=[40, 40]), box("box", [0.0, 0.5, 0.0], [1, 1, 1])],
                  lights=[AreaLight("sphere", [0.5002, 1.0002, 0.4998], radius=1e-4, samples=8)],
                  width=192, height=144)
    with Renderer(scene, ctx) as r:
        res = {run: r.render(*run) for run in [("auto", "cpu"), ("zfail", "cpu"), ("zfail", "gpu")]}
    assert not res["auto", "cpu"].zfail.any()
    for run in [("zfail", "cpu"), ("zfail", "gpu")]:
        np.testing.assert_array_equal(res[run].lit_count, res["auto", "cpu"].lit_count, str(run))
