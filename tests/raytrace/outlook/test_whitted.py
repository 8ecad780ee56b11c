"""The Whitted renderer against colours computed by hand: the Phong local term, mirrors, the
weighted sum and the depth limit, transparency, hard shadows, spot cones, the background."""

import io
import math

import numpy as np
import pytest
from builders import SCENES

import raytrace
from raytrace.outlook.progress import Progress
from shadowvol.primitives import plane, sphere
from shadowvol.scene import Camera, Material, PointLight, Scene, SpotLight
from shadowvol.scenefile import load_scene

N = 9  # odd: the centre pixel's ray runs straight down the view axis
CAMERA = Camera(eye=[0.0, 0.0, 4.0], target=[0.0, 0.0, 0.0], fov_y=40.0)
BG = np.array([0.2, 0.3, 0.4])


def matte(ka, kd=(0, 0, 0), ks=(0, 0, 0), shininess=1.0, **kw):
    return Material(ambient=list(ka), diffuse=list(kd), specular=list(ks), shininess=shininess,
                    **kw)


def facing_quad(name="quad", z=0.0, material=None, size=4.0):
    return plane(name, point=[0, 0, z], normal=[0, 0, 1], size=[size, size], material=material)


def scene_of(objects, lights=(), **kw):
    return Scene(camera=CAMERA, objects=objects, lights=list(lights), width=N, height=N,
                 ambient=[0.5, 0.5, 0.5], background=list(BG), **kw)


def centre(image):
    return image[N // 2, N // 2]


def test_phong_by_hand():
    ka, kd, ks, shininess = [0.1, 0.2, 0.3], [0.5, 0.4, 0.3], [0.2, 0.2, 0.2], 10.0
    light = PointLight([1.0, 1.0, 3.0], color=[1.0, 0.5, 0.25], intensity=2.0)
    scene = scene_of([facing_quad(material=matte(ka, kd, ks, shininess))], [light])
    # At p = 0 with n = v = +z: l = (1,1,3)/sqrt(11), r = 2(n.l)n - l = (-1,-1,3)/sqrt(11).
    n_dot_l = r_dot_v = 3 / math.sqrt(11)
    expect = (np.multiply(ka, 0.5)
              + (np.multiply(kd, n_dot_l) + np.multiply(ks, r_dot_v ** shininess))
              * np.array([2.0, 1.0, 0.5]))
    assert centre(raytrace.render(scene, max_depth=0)) == pytest.approx(expect, rel=1e-12)
    # No distance attenuation: twice as far along the same direction, the same colour.
    far = scene.replace(lights=(PointLight([2.0, 2.0, 6.0], color=[1.0, 0.5, 0.25],
                                           intensity=2.0),))
    assert centre(raytrace.render(far, max_depth=0)) == pytest.approx(expect, rel=1e-12)


def test_light_behind_the_surface_and_background():
    scene = scene_of([facing_quad(material=matte([0.1, 0.1, 0.1], [1, 1, 1], [1, 1, 1]),
                                  size=1.0)], [PointLight([0.0, 0.0, -2.0])])
    image = raytrace.render(scene, max_depth=0)
    assert centre(image) == pytest.approx([0.05, 0.05, 0.05])  # n.l < 0: ambient alone
    assert np.array_equal(image[0, 0], BG)  # the corner ray misses: the background


def test_mirror_weighted_sum_and_depth_limit():
    """A half mirror at z = 0 reflects the centre ray back along +z onto a quad behind the
    camera.  No lights: each local term is ka * ambient."""
    mirror = facing_quad("mirror", material=matte([0.2, 0.0, 0.0], reflectivity=0.5))
    back = plane("back", point=[0, 0, 6], normal=[0, 0, -1], size=[1, 1],
                 material=matte([0.0, 0.8, 0.0]))
    scene = scene_of([mirror, back])
    local_mirror, local_back = np.array([0.1, 0, 0]), np.array([0, 0.4, 0])
    # Depth 0: the mirror's local term alone, unweighted.
    assert centre(raytrace.render(scene, max_depth=0)) == pytest.approx(local_mirror)
    # Depth 1: local * (1 - 0.5) + 0.5 * (what the reflected ray sees).
    expect = 0.5 * local_mirror + 0.5 * local_back
    assert centre(raytrace.render(scene, max_depth=1)) == pytest.approx(expect)
    # A reflected ray that misses everything brings the background.
    corner = raytrace.render(scene.replace(objects=(mirror,)), max_depth=1)
    assert centre(corner) == pytest.approx(0.5 * local_mirror + 0.5 * BG)


def test_facing_mirrors_stop_at_the_depth_limit():
    """Two full mirrors facing each other: the ray bounces until max_depth, where the local term
    counts unweighted, so the colour is that of the last surface reached."""
    a = facing_quad("a", z=0.0, material=matte([0.4, 0, 0], reflectivity=1.0))
    b = plane("b", point=[0, 0, 8], normal=[0, 0, -1], size=[40, 40],
              material=matte([0, 0, 0.4], reflectivity=1.0))
    scene = scene_of([a, b])
    for depth, colour in [(0, [0.2, 0, 0]), (1, [0, 0, 0.2]), (4, [0.2, 0, 0]), (5, [0, 0, 0.2])]:
        assert centre(raytrace.render(scene, max_depth=depth)) == pytest.approx(colour)


def test_transparent_plane_with_ior_one_is_a_window():
    """transparency 1 and ior 1: rays pass unbent, so the image is the scene without it."""
    glass = facing_quad("glass", z=1.0, material=matte([0, 0, 0], transparency=1.0, ior=1.0))
    wall = facing_quad("wall", z=-1.0, material=matte([0.3, 0.6, 0.9]), size=2.0)
    scene = scene_of([glass, wall])
    with_glass = raytrace.render(scene, max_depth=2)
    without = raytrace.render(scene.replace(objects=(wall,)), max_depth=2)
    assert np.allclose(with_glass, without, atol=1e-12)
    assert not np.allclose(raytrace.render(scene, max_depth=0), without)  # depth 0: no window


def test_glass_sphere_centre_ray_goes_straight_through():
    """At normal incidence Snell's law does not bend: through a glass ball on the axis the centre
    ray reaches a wall behind it at the same point as without the ball."""
    ball = sphere("ball", [0, 0, 0], 1.0, material=matte([0, 0, 0], transparency=1.0, ior=1.5))
    wall = facing_quad("wall", z=-3.0, material=matte([0.3, 0.6, 0.9]), size=0.1)
    scene = scene_of([ball, wall])
    image = raytrace.render(scene, max_depth=3)
    assert centre(image) == pytest.approx([0.15, 0.3, 0.45])
    # Off the axis the ball is a lens (focal length nR / 2(n - 1) = 1.5 from its centre): it
    # images the wall close in front of the camera, magnified, where the bare wall covers a
    # single pixel at 41 x 41.
    def wall_pixels(objects):
        im = raytrace.render(scene.replace(objects=objects, width=41, height=41), max_depth=3)
        return int((np.abs(im - [0.15, 0.3, 0.45]).max(axis=2) < 1e-9).sum())

    assert wall_pixels((wall,)) == 1
    assert wall_pixels((ball, wall)) > 9


def test_transparent_objects_cast_hard_shadows_and_spot_cones():
    """Straight above the floor point, a glass ball blocks the light (transparent objects are
    opaque to shadow rays); a spot light lights only inside its cone."""
    floor = facing_quad("floor", material=matte([0.2, 0.2, 0.2], [0.6, 0.6, 0.6]), size=20)
    ball = sphere("ball", [0, 0, 2.0], 0.3, material=matte([0, 0, 0], transparency=0.9))
    cam = Camera(eye=[0.0, 2.0, 4.0], target=[0.0, 0.0, 0.0], fov_y=40.0)
    above = PointLight([0.0, 0.0, 3.5])
    scene = scene_of([floor, ball], [above]).replace(camera=cam, width=41, height=41)
    # The pixel whose ray hits the floor at the origin (the centre pixel: target = origin).
    assert raytrace.render(scene, max_depth=0)[20, 20] == pytest.approx([0.1, 0.1, 0.1])
    unblocked = raytrace.render(scene.replace(objects=(floor,)), max_depth=0)[20, 20]
    assert unblocked == pytest.approx([0.1 + 0.6, 0.1 + 0.6, 0.1 + 0.6])  # n.l = 1
    spot_in = SpotLight([0.0, 0.0, 3.5], direction=[0.0, 0.3, -1.0], cone_angle=20.0)
    spot_out = SpotLight([0.0, 0.0, 3.5], direction=[0.0, 0.5, -1.0], cone_angle=20.0)
    # The axis tilts by 16.7 and 26.6 degrees away from the straight-down ray to the origin.
    lit_in = raytrace.render(scene.replace(objects=(floor,), lights=(spot_in,)), max_depth=0)
    lit_out = raytrace.render(scene.replace(objects=(floor,), lights=(spot_out,)), max_depth=0)
    assert lit_in[20, 20] == pytest.approx([0.7, 0.7, 0.7])
    assert lit_out[20, 20] == pytest.approx([0.1, 0.1, 0.1])


def test_whitted_scene_both_backends_and_depth():
    """The example scene (mirror ball, glass ball, red box, floor): the box goes through the
    triangle backend; both backends render the same image.  Reflections change the balls only."""
    scene = load_scene(SCENES / "whitted.toml").replace(width=80, height=60)
    a = raytrace.render(scene, backend="embree")
    b = raytrace.render(scene, backend="numpy")
    assert a.shape == (60, 80, 3) and a.dtype == np.float64
    assert np.mean(np.abs(a - b) > 1e-9) < 0.002  # float32 edge decisions on the box, if any
    direct = raytrace.render(scene, max_depth=0)
    changed = np.abs(a - direct).max(axis=2) > 1e-9
    assert 0.05 < changed.mean() < 0.4  # the two balls and little else
    assert np.array_equal(a[0], direct[0])  # the sky is the sky


def test_bad_max_depth():
    with pytest.raises(ValueError, match="max_depth"):
        raytrace.render(scene_of([facing_quad()]), max_depth=-1)


def test_progress_bar_only_on_a_terminal():
    quiet = io.StringIO()
    with Progress(3, "x", stream=quiet) as bar:  # StringIO is not a terminal
        for _ in range(3):
            bar.update()
    assert quiet.getvalue() == ""
    shown = io.StringIO()
    bar = Progress(3, "render", enabled=True, stream=shown)
    bar.DELAY = 0.0
    with bar:
        for _ in range(3):
            bar.update()
    assert "render [" in shown.getvalue() and "100%" in shown.getvalue()
    assert shown.getvalue().endswith("\n")
