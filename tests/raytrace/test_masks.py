"""Reference masks against expectations computed by hand.

A sphere over a plane: its shadow from a point light is where the plane cuts the light's cone
tangent to the sphere, a conic (here an ellipse); from a directional light, where it cuts the
tangent cylinder.  A spot light's lit region on the plane is the cut of its cone.  The masks are
traced on the tessellated sphere, the expectation uses the exact one, so mismatches are allowed
only within `BAND` pixel of an expected edge, and at most one per 20 edge pixels.
"""


import numpy as np
from builders import TEST_OUTPUT
from scipy.ndimage import binary_dilation

import raytrace
from raytrace.camera import primary_rays
from raytrace.intersect import ray_sphere
from shadowvol.io import save_png
from shadowvol.pictures import masks_image
from shadowvol.primitives import plane, sphere
from shadowvol.scene import Camera, DirectionalLight, PointLight, Scene, SpotLight

OUT = TEST_OUTPUT

CENTRE, RADIUS = np.array([0.2, 1.0, -0.3]), 0.6
FLOOR = 30.0
BAND = 1  # pixel: the tessellation (icosphere level 4) moves edges by less than a pixel here
W, H = 160, 120


def sphere_scene(*lights):
    return Scene(camera=Camera(eye=[0.0, 4.0, 6.0], target=[0.0, 0.5, 0.0], fov_y=45.0),
                 objects=[plane("floor", size=[FLOOR, FLOOR]),
                          sphere("ball", CENTRE, RADIUS, subdivisions=4)],
                 lights=list(lights), width=W, height=H)


def exact_view(scene):
    """Per pixel: which exact surface the centre ray sees and where.

    Returns on_ball (H*W,) bool, on_floor (H*W,) bool, point (H*W, 3), normal (H*W, 3)."""
    o, d = primary_rays(scene.camera, W, H)
    t_ball = ray_sphere(o, d, CENTRE, RADIUS)
    t_floor = np.where(d[:, 1] < 0, -o[:, 1] / d[:, 1], np.inf)  # the plane y = 0, by hand
    foot = o + np.where(np.isfinite(t_floor), t_floor, 0)[:, None] * d
    t_floor[np.abs(foot[:, [0, 2]]).max(axis=1) > FLOOR / 2] = np.inf  # it is 30 x 30
    on_ball = t_ball < t_floor
    on_floor = ~on_ball & np.isfinite(t_floor)
    t = np.where(on_ball, t_ball, t_floor)
    p = o + np.where(np.isfinite(t), t, 0)[:, None] * d
    normal = np.where(on_ball[:, None], (p - CENTRE) / RADIUS, [0.0, 1.0, 0.0])
    return on_ball, on_floor, p, normal


def in_cone(p, apex, axis, cos_half):
    """Points p (n, 3) inside the infinite cone from `apex` along unit `axis` with half-angle
    acos(cos_half), on the axis' side: ((p−apex)·axis)² >= cos² |p−apex|² and (p−apex)·axis > 0.
    Cut by a plane this is the conic of the course."""
    v = p - apex
    along = v @ axis
    return (along > 0) & (along ** 2 >= cos_half ** 2 * np.einsum("ij,ij->i", v, v))


def expected_masks(scene):
    on_ball, on_floor, p, normal = exact_view(scene)
    lit = []
    for light in scene.lights:
        if isinstance(light, DirectionalLight):
            l = -light.direction
            facing = normal @ l > 0
            # Shadow cylinder: distance from the axis through the centre < R, on the far side.
            v = p - CENTRE
            dist2 = np.einsum("ij,ij->i", v, v) - (v @ l) ** 2
            shadow = on_floor & (dist2 < RADIUS ** 2) & (v @ l < 0)
        else:
            to_c = CENTRE - light.position
            dist = np.linalg.norm(to_c)
            cos_tangent = np.sqrt(1 - (RADIUS / dist) ** 2)  # cone tangent to the sphere
            shadow = on_floor & in_cone(p, light.position, to_c / dist, cos_tangent)
            # A light under the floor: the floor itself shadows everything above it.
            L = light.position
            with np.errstate(divide="ignore", invalid="ignore"):
                cross = p + (L - p) * (p[:, 1] / (p[:, 1] - L[1]))[:, None]
            shadow |= (L[1] < 0) & (p[:, 1] > 0) & (np.abs(cross[:, [0, 2]]).max(axis=1)
                                                     <= FLOOR / 2)
            facing = np.einsum("ij,ij->i", normal, light.position - p) > 0
            if isinstance(light, SpotLight):
                facing &= in_cone(p, light.position, light.direction, light.cos_cutoff)
        lit.append(((on_ball | on_floor) & facing & ~shadow).reshape(H, W))
    return np.array(lit), (on_ball | on_floor).reshape(H, W)


def check(scene, name, max_per_edge_pixel=0.05):
    lit, coverage = raytrace.shadow_masks(scene)
    ref_lit, ref_cov = expected_masks(scene)
    assert lit.dtype == bool and lit.shape == (len(scene.lights), H, W)
    assert coverage.dtype == bool and coverage.shape == (H, W)
    for got, ref, what in [(coverage, ref_cov, "coverage")] + [
            (lit[i], ref_lit[i], f"light {i}") for i in range(len(lit))]:
        edges = (ref != np.roll(ref, 1, 0)) | (ref != np.roll(ref, 1, 1))
        band = binary_dilation(edges, iterations=BAND)
        bad = got != ref
        ok = not (bad & ~band).any() and bad.sum() <= max_per_edge_pixel * edges.sum()
        if not ok:  # leave the evidence where the test output goes
            save_png(OUT / name / "masks.png", masks_image(lit, coverage))
            save_png(OUT / name / "expected.png", masks_image(ref_lit, ref_cov))
            diff = np.zeros(ref.shape + (3,), np.uint8)
            diff[band] = 60  # where mismatches are allowed
            diff[bad & got] = (40, 80, 255)  # traced True, expected False
            diff[bad & ~got] = (230, 30, 30)  # traced False, expected True
            save_png(OUT / name / f"diff-{what.replace(' ', '')}.png", diff)
        assert not (bad & ~band).any(), f"{what}: {(bad & ~band).sum()} mismatches off the edges"
        assert bad.sum() <= max_per_edge_pixel * edges.sum(), \
            f"{what}: {bad.sum()} mismatches along {edges.sum()} edge pixels"
    # The expectation must have something to test: a shadow, or an unlit side, in every slice
    # of a light that lights anything at all.
    for ref in ref_lit:
        assert not ref.any() or (ref_cov & ~ref).sum() > 100
    return lit, coverage


def test_point_light_shadow_is_the_conic():
    lit, _ = check(sphere_scene(PointLight([-2.0, 5.0, 1.5])), "point")
    assert 0.02 < 1 - lit.mean() < 0.9


def test_directional_light_shadow_is_the_cylinder_cut():
    check(sphere_scene(DirectionalLight([0.5, -1.0, -0.4])), "directional")


def test_spot_light_cone_and_shadow():
    spot = SpotLight([1.0, 4.0, 0.0], direction=[-0.2, -1.0, 0.1], cone_angle=25.0)
    check(sphere_scene(spot), "spot")


def test_lights_in_scene_order_and_light_behind_the_floor():
    """Two lights: slice i is light i.  A light under the floor lights nothing the camera sees:
    the floor faces away from it, and it shadows the ball's lower half, which faces it."""
    scene = sphere_scene(PointLight([-2.0, 5.0, 1.5]), PointLight([0.0, -3.0, 0.0]))
    lit, coverage = check(scene, "two-lights")
    single, _ = raytrace.shadow_masks(sphere_scene(PointLight([-2.0, 5.0, 1.5])))
    assert np.array_equal(lit[0], single[0])
    assert not lit[1].any()


def test_quad_facing_the_camera_by_hand():
    """A square at z = 0 seen from z = 4 with fov 90 degrees: its coverage is exactly the pixels
    whose centres project inside it (edges chosen between pixel centres: no tolerance).  A light
    behind it lights nothing (two-sided: the normal faces the camera); one in front lights all."""
    # 20 x 20 image, half-width of the view at z = 0 is 4 (tan 45° x 4); the quad spans x, y in
    # [-1.1, 1.1] -> NDC [-0.275, 0.275].  Pixel centres (x + 0.5) / 20 * 2 - 1 inside: x = 7
    # (-0.25) .. 12 (0.25), not 6 (-0.35) or 13: a 6 x 6 block, rows and columns 7..12.
    quad = plane("quad", point=[0, 0, 0], normal=[0, 0, 1], size=[2.2, 2.2])
    scene = Scene(camera=Camera(eye=[0, 0, 4], target=[0, 0, 0], fov_y=90.0), objects=[quad],
                  lights=[PointLight([0, 0, -3]), PointLight([0.5, 0.5, 2])], width=20, height=20)
    lit, coverage = raytrace.shadow_masks(scene)
    expect = np.zeros((20, 20), bool)
    expect[7:13, 7:13] = True
    assert np.array_equal(coverage, expect)
    assert not lit[0].any()
    assert np.array_equal(lit[1], expect)


def test_near_plane_clips_geometry():
    """A quad nearer than the near plane is not seen; the rays start on the near plane."""
    quad = plane("quad", point=[0, 0, 3.95], normal=[0, 0, 1], size=[2.0, 2.0])
    far = plane("far", point=[0, 0, -5], normal=[0, 0, 1], size=[3.0, 3.0])
    cam = Camera(eye=[0, 0, 4], target=[0, 0, 0], fov_y=60.0, near=0.1)
    scene = Scene(camera=cam, objects=[quad, far], lights=[PointLight([0, 0, 0])],
                  width=16, height=16)
    lit, coverage = raytrace.shadow_masks(scene)
    # Only the far square is seen (the clipped quad would have covered everything), and the
    # light between them reaches it.  At depth 9 its half-size 1.5 is NDC 1.5 / 9 / tan 30° =
    # 0.289: the pixel centres at NDC ±0.0625 and ±0.1875, a 4 x 4 block.
    expect = np.zeros((16, 16), bool)
    expect[6:10, 6:10] = True
    assert np.array_equal(coverage, expect)
    assert np.array_equal(lit[0], coverage)
    _, cov_near = raytrace.shadow_masks(scene.replace(camera=Camera(
        eye=[0, 0, 4], target=[0, 0, 0], fov_y=60.0, near=0.01)))
    assert cov_near.all()


def test_numpy_and_embree_give_the_same_masks():
    scene = sphere_scene(PointLight([-2.0, 5.0, 1.5]), DirectionalLight([0.5, -1.0, -0.4]))
    scene = scene.replace(width=64, height=48)
    lit, coverage = raytrace.shadow_masks(scene, backend="embree")
    lit2, coverage2 = raytrace.shadow_masks(scene, backend="numpy")
    assert np.array_equal(coverage, coverage2)
    assert (lit != lit2).sum() <= 2  # float32 vs float64 at a shadow edge, if anywhere
    assert 0.1 < lit.mean() < 0.9
