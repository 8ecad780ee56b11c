"""The pyrender bridge: conversion both ways, the NumPy 2 shim, EGL coexistence with moderngl,
and pyrender's shadow-mapped image and masks against an analytic reference."""

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from shadowvol.compare import pyrender_peer as pb
from shadowvol.io import save_png
from shadowvol.pictures import masks_image
from shadowvol.primitives import box, plane, sphere
from shadowvol.scene import (
    Camera,
    DirectionalLight,
    Material,
    PointLight,
    Scene,
    SpotLight,
)

FLOAT32 = 1e-6       # pyrender stores positions as float32: relative round-trip error
REPO = Path(__file__).resolve().parents[1]


BOX = (np.array([-0.5, 0.5, -0.5]), np.array([0.5, 1.5, 0.5]))
WALL_Z, WALL_X, WALL_Y = -1.5, (-1.5, 1.5), (0.0, 1.5)     # a vertical quad facing +z


def _light_box_scene(width=64, height=48, **changes):
    """A unit box (y in [0.5, 1.5]) over an 8 x 8 floor, a spot light 4 above the box's centre
    shining straight down with a 40 degree half-angle, the camera above and in front."""
    scene = Scene(camera=Camera(eye=[0.0, 5.0, 2.5], target=[0.0, 0.0, 0.0], fov_y=50.0),
                  objects=[plane("floor", size=[8.0, 8.0],
                                 material=Material(diffuse=[0.8, 0.75, 0.6])),
                           box("box", [0.0, 1.0, 0.0], [1.0, 1.0, 1.0],
                               material=Material(diffuse=[0.3, 0.5, 0.9]))],
                  lights=[SpotLight([0.0, 4.0, 0.0], [0.0, -1.0, 0.0], 40.0)],
                  width=width, height=height, ambient=[0.2, 0.2, 0.2])
    return scene.replace(**changes) if changes else scene


def _wall_sun_scene(width=64, height=48, wall_winding=-1.0):
    """The box and floor, plus an open wall (one quad) behind the box, under a directional light
    coming from behind the wall: the wall's visible side faces away from the light but nothing
    lies between it and the light, so only the n . l test can say it is unlit.

    wall_winding : the z of the wall's winding normal.  -1 winds it toward the light (its back,
    by winding, faces the camera: our surfaces are two-sided, so that changes nothing for us);
    pyrender's shadow pass culls faces wound away from the light (see the bridge's docstring)."""
    wall = plane("wall", point=[0.0, 0.75, WALL_Z], normal=[0.0, 0.0, wall_winding],
                 size=[3.0, 1.5])
    base = _light_box_scene(width, height)
    return base.replace(objects=[*base.objects, wall],
                        lights=[DirectionalLight([0.3, -1.0, 0.6])],
                        camera=Camera(eye=[0.0, 4.0, 5.0], target=[0.0, 0.3, -0.5], fov_y=55.0))


def _pixel_rays(scene):
    """Camera rays through the pixel centres (CONVENTIONS.md): eye (3,), directions (H, W, 3)."""
    cam = scene.camera
    H, W = scene.height, scene.width
    t = math.tan(math.radians(cam.fov_y) / 2)
    xs = ((np.arange(W) + 0.5) / W * 2 - 1) * t * scene.aspect
    ys = (1 - (np.arange(H) + 0.5) / H * 2) * t
    X, Y = np.meshgrid(xs, ys)
    return cam.eye, np.stack([X, Y, -np.ones_like(X)], -1) @ pb.camera_pose(cam)[:3, :3].T


def _hit_box(o, d):
    """Slab test against BOX: (hit (..), t (..), outward normal of the entry face (.., 3))."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t1, t2 = (BOX[0] - o) / d, (BOX[1] - o) / d
    tn = np.minimum(t1, t2)
    tnear, tfar = tn.max(-1), np.maximum(t1, t2).min(-1)
    axis = tn.argmax(-1)
    normal = -np.sign(d) * (np.arange(3) == axis[..., None])
    return (tnear <= tfar) & (tnear > 0), tnear, normal


def _hit_wall(o, d):
    """(hit (..), t (..)) against the wall quad z = WALL_Z."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (WALL_Z - o[..., 2]) / d[..., 2]
    p = o + t[..., None] * d
    return ((t > 0) & (p[..., 0] >= WALL_X[0]) & (p[..., 0] <= WALL_X[1])
            & (p[..., 1] >= WALL_Y[0]) & (p[..., 1] <= WALL_Y[1])), t


def _expected_masks(scene, wall=False):
    """Analytic classes of every pixel at its centre, for the scenes above.

    The camera ray hits the nearest of the box (slab test), the wall (if any) and the floor.
    A point is lit when its normal, flipped toward the camera, has n . l > 0, a spot light's
    cone contains it, and the ray from it toward the light misses the box and the wall (the box
    is convex, so it never shadows its own lit faces; nothing lies below the floor).
    For the spot scene this gives the shadow square |x|, |z| <= 0.8 on the floor: the light sits
    above the top face's centre, so the box's silhouette is the top face, scaled from the light
    by 4 / (4 - 1.5) = 1.6.

    Returns a dict of (H, W) bool: lit, coverage, box (the ray hits the box), floor_shadow
    (the ray hits the floor and the floor point is shadowed).
    """
    o, d = _pixel_rays(scene)
    far = np.full(d.shape[:2], np.inf)
    hb, tb, nb = _hit_box(o, d)
    hw, tw = _hit_wall(o, d) if wall else (np.zeros_like(hb), far)
    tf = -o[1] / d[..., 1]
    pf = o + tf[..., None] * d
    hf = (tf > 0) & (np.abs(pf[..., 0]) <= 4) & (np.abs(pf[..., 2]) <= 4)
    t = np.stack([np.where(hb, tb, far), np.where(hw, tw, far), np.where(hf, tf, far)])
    which = np.where(np.isinf(t.min(0)), -1, t.argmin(0))         # 0 box, 1 wall, 2 floor
    P = o + np.where(np.isinf(t.min(0)), 0.0, t.min(0))[..., None] * d
    normal = np.select([which[..., None] == 0, which[..., None] == 1],
                       [nb, np.array([0.0, 0.0, 1.0])], np.array([0.0, 1.0, 0.0]))
    normal = normal * np.where(np.sum(normal * (o - P), -1) < 0, -1, 1)[..., None]
    light = scene.lights[0]
    if isinstance(light, DirectionalLight):
        to_light = np.broadcast_to(-light.direction, P.shape)
        cone = np.ones(P.shape[:2], bool)
    else:
        to_light = light.position - P
        cone = (np.sum(-to_light * light.direction, -1) / np.linalg.norm(to_light, axis=-1)
                >= light.cos_cutoff)
    facing = np.sum(normal * to_light, -1) > 0
    start = P + 1e-9 * to_light
    blocked = _hit_box(start, to_light)[0] | (wall & _hit_wall(start, to_light)[0])
    if not isinstance(light, DirectionalLight):   # only blockers before the light count
        tb2 = _hit_box(start, to_light)[1]
        blocked = (_hit_box(start, to_light)[0] & (tb2 < 1)) | \
            (wall & _hit_wall(start, to_light)[0] & (_hit_wall(start, to_light)[1] < 1))
    covered = which >= 0
    return dict(lit=covered & facing & cone & ~blocked, coverage=covered, box=which == 0,
                floor_shadow=(which == 2) & blocked)


def _edges(*masks):
    """(H, W) bool: pixels within one pixel (8-neighbourhood) of a change in any mask."""
    edge = np.zeros(masks[0].shape, bool)
    for m in masks:
        p = np.pad(m, 1, mode="edge")
        H, W = m.shape
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                edge |= p[1 + dy:1 + dy + H, 1 + dx:1 + dx + W] != m
    return edge


def _save_failure(tmp_path, name, got, want, coverage_got, coverage_want):
    big = np.ones((4, 4, 1), np.uint8)
    save_png(tmp_path / f"{name}_pyrender.png", np.kron(masks_image(got[None], coverage_got), big))
    save_png(tmp_path / f"{name}_expected.png",
             np.kron(masks_image(want[None], coverage_want), big))
    diff = np.zeros(got.shape + (3,), np.uint8)
    diff[got & ~want] = (255, 0, 0)
    diff[~got & want] = (0, 0, 255)
    save_png(tmp_path / f"{name}_diff.png", np.kron(diff, big))
    return tmp_path


# ---------------------------------------------------------------------------------------------

def test_shim_makes_pyrender_importable_under_numpy_2():
    # A fresh interpreter: NumPy 2 has no np.infty; importing the bridge must not import
    # pyrender; the first use adds the alias, sets PYOPENGL_PLATFORM=egl (it was unset) and
    # pyrender's Mesh.bounds (which uses np.infty) works.
    code = """if True:
        import os, sys
        import numpy as np
        assert int(np.__version__.split('.')[0]) >= 2, np.__version__
        assert not hasattr(np, 'infty')
        import shadowvol.compare.pyrender_peer as pb
        assert 'pyrender' not in sys.modules and 'OpenGL' not in sys.modules
        pyrender = pb.import_pyrender()
        assert np.infty == np.inf
        assert os.environ['PYOPENGL_PLATFORM'] == 'egl'
        import trimesh
        m = pyrender.Mesh.from_trimesh(trimesh.creation.box())
        assert np.allclose(m.bounds, [[-0.5] * 3, [0.5] * 3])
        print('ok')
    """
    env = {k: v for k, v in os.environ.items() if k != "PYOPENGL_PLATFORM"}
    env["PYTHONPATH"] = str(REPO) + os.pathsep + env.get("PYTHONPATH", "")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         timeout=120)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr


def test_round_trip_keeps_triangles_camera_and_lights():
    scene = Scene(
        camera=Camera(eye=[1.0, 3.0, 6.0], target=[0.0, 0.5, 0.0], up=[0.1, 1.0, 0.0],
                      fov_y=40.0, near=0.1),
        objects=[plane("floor", size=[10.0, 6.0]),
                 box("crate", [1.0, 0.5, -1.0], [1.0, 2.0, 0.5],
                     material=Material(diffuse=[0.9, 0.2, 0.1], shininess=50.0)),
                 sphere("ball", [-1.0, 1.0, 0.5], 0.7, subdivisions=1)],
        lights=[SpotLight([0.0, 5.0, 1.0], [0.1, -1.0, -0.2], 35.0, color=[1.0, 0.9, 0.8],
                          intensity=0.7),
                DirectionalLight([0.3, -1.0, -0.4], intensity=0.5),
                PointLight([-2.0, 4.0, 3.0], color=[0.5, 0.5, 1.0], intensity=0.3)],
        width=80, height=60)
    pr = pb.to_pyrender(scene)
    back = pb.from_pyrender(pr, scene.width, scene.height)
    scale = scene.extent
    assert sorted(o.name for o in back.objects) == ["ball", "crate", "floor"]
    by_name = {o.name: o for o in back.objects}
    for obj in scene.objects:
        np.testing.assert_allclose(by_name[obj.name].triangles, obj.triangles,
                                   atol=FLOAT32 * scale)
    np.testing.assert_allclose(by_name["crate"].material.diffuse, [0.9, 0.2, 0.1], rtol=FLOAT32)
    assert by_name["crate"].material.shininess == pytest.approx(50.0, rel=1e-5)
    np.testing.assert_allclose(pb.camera_pose(back.camera), pb.camera_pose(scene.camera),
                               atol=1e-12)
    assert back.camera.fov_y == pytest.approx(40.0) and back.camera.near == pytest.approx(0.1)
    assert [type(l) for l in back.lights] == [SpotLight, DirectionalLight, PointLight]
    spot, sun, point = back.lights
    np.testing.assert_allclose(spot.position, [0.0, 5.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(spot.direction, scene.lights[0].direction, atol=1e-12)
    assert spot.cone_angle == pytest.approx(35.0)
    np.testing.assert_allclose(sun.direction, scene.lights[1].direction, atol=1e-12)
    np.testing.assert_allclose(point.position, [-2.0, 4.0, 3.0], atol=1e-12)
    for got, want in zip(back.lights, scene.lights):
        np.testing.assert_allclose(got.color, want.color, atol=1e-12)
        assert got.intensity == pytest.approx(want.intensity, rel=1e-5)


def test_from_pyrender_applies_node_poses_and_drops_points():
    import trimesh
    pyrender = pb.import_pyrender()
    pr = pyrender.Scene()
    cube = trimesh.creation.box(extents=[1.0, 1.0, 1.0])
    parent = pyrender.Node(name="rig", matrix=np.array([[1, 0, 0, 10], [0, 1, 0, 0],
                                                        [0, 0, 1, 0], [0, 0, 0, 1.0]]))
    pr.add_node(parent)
    pose = np.eye(4)
    pose[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]         # 90 degrees about z
    pose[:3, 3] = [1.0, 2.0, 3.0]
    pr.add(pyrender.Mesh.from_trimesh(cube, smooth=False), name="cube", pose=pose,
           parent_node=parent)
    pr.add(pyrender.Mesh.from_points(np.zeros((5, 3))), name="cloud")
    cam_pose = np.eye(4)
    cam_pose[:3, 3] = [0, 0, 10]
    pr.add(pyrender.PerspectiveCamera(yfov=0.8, znear=0.2), pose=cam_pose)
    scene = pb.from_pyrender(pr, 32, 24)
    assert [o.name for o in scene.objects] == ["cube"]
    # World = parent (x + 10) @ pose (rotate, then + (1, 2, 3)): the cube's corner (0.5, 0.5,
    # 0.5) goes to (-0.5, 0.5, 0.5) + (1, 2, 3) + (10, 0, 0) = (10.5, 2.5, 3.5).
    v = scene.objects[0].vertices
    np.testing.assert_allclose(v.min(axis=0), [10.5, 1.5, 2.5], atol=FLOAT32)
    np.testing.assert_allclose(v.max(axis=0), [11.5, 2.5, 3.5], atol=FLOAT32)
    np.testing.assert_allclose(scene.camera.eye, [0, 0, 10])
    np.testing.assert_allclose(scene.camera.target, [0, 0, 9])
    assert scene.camera.fov_y == pytest.approx(math.degrees(0.8)) and scene.lights == ()


def test_point_lights_have_no_pyrender_mask():
    scene = _light_box_scene(lights=[SpotLight([0.0, 4.0, 0.0], [0.0, -1.0, 0.0], 40.0),
                                     PointLight([1.0, 3.0, 0.0])])
    assert pb.maskable_lights(scene) == (0,)
    with pytest.raises(ValueError, match="point light"):
        pb.pyrender_shadow_masks(scene)


def test_render_shows_the_box_shadow_where_geometry_puts_it(tmp_path):
    scene = _light_box_scene()
    want = _expected_masks(scene)
    img = pb.render_pyrender(scene, shadows=True)
    plain = pb.render_pyrender(scene, shadows=False)
    assert img.shape == (48, 64, 3) and img.dtype == np.uint8
    # Away from every edge: floor pixels in the shadow square, and lit floor pixels.
    inner = ~_edges(want["lit"], want["coverage"], want["box"], want["floor_shadow"])
    shadow_px = inner & want["floor_shadow"]
    lit_px = inner & want["lit"] & ~want["box"]
    assert shadow_px.sum() >= 20 and lit_px.sum() >= 200, (shadow_px.sum(), lit_px.sum())
    luma, luma_plain = img.astype(float).mean(-1), plain.astype(float).mean(-1)
    dark = luma[shadow_px].max() < 0.5 * luma[lit_px].min()
    bright_without = luma_plain[shadow_px].min() > 0.5 * luma[lit_px].min()
    if not (dark and bright_without):
        big = np.ones((4, 4, 1), np.uint8)
        save_png(tmp_path / "shadows.png", np.kron(img, big))
        save_png(tmp_path / "no_shadows.png", np.kron(plain, big))
        pytest.fail(f"shadow {luma[shadow_px].max()} vs lit {luma[lit_px].min()} (without "
                    f"shadows {luma_plain[shadow_px].min()}); images in {tmp_path}")


def test_shadow_masks_match_the_analytic_masks(tmp_path):
    # Budget: no mismatch farther than one pixel from an edge of the expected masks (pyrender's
    # 2048^2 spot shadow map has texels ~0.01 units here, far below a pixel's ~0.1 footprint),
    # and at the edges (multisampled blends, the cone's 0.1 degree ramp) at most a quarter of the
    # edge pixels.
    scene = _light_box_scene()
    want = _expected_masks(scene)
    lit, coverage = pb.pyrender_shadow_masks(scene)
    assert lit.shape == (1, 48, 64) and lit.dtype == bool and coverage.dtype == bool
    edge = _edges(want["lit"], want["coverage"])
    wrong = (lit[0] != want["lit"]) | (coverage != want["coverage"])
    if wrong[~edge].any() or wrong[edge].sum() > edge.sum() // 4:
        where = _save_failure(tmp_path, "box", lit[0], want["lit"], coverage, want["coverage"])
        pytest.fail(f"{int(wrong[~edge].sum())} interior and {int(wrong[edge].sum())} of "
                    f"{int(edge.sum())} edge mismatches; masks in {where}")
    # The shadow is there at all: floor pixels in the shadow square are covered and not lit.
    assert (coverage & ~lit[0])[want["floor_shadow"] & ~edge].all()
    assert want["floor_shadow"][~edge].sum() >= 20


def test_shadow_masks_know_a_face_turned_away_from_an_unblocked_light(tmp_path):
    # Directional light from behind an open wall: the wall's visible side has n . l < 0 with
    # nothing between it and the light, the box's and the wall's shadows fall on the floor.
    # Same budget as above.
    scene = _wall_sun_scene()
    want = _expected_masks(scene, wall=True)
    lit, coverage = pb.pyrender_shadow_masks(scene)
    edge = _edges(want["lit"], want["coverage"])
    wrong = (lit[0] != want["lit"]) | (coverage != want["coverage"])
    if wrong[~edge].any() or wrong[edge].sum() > edge.sum() // 4:
        where = _save_failure(tmp_path, "wall", lit[0], want["lit"], coverage, want["coverage"])
        pytest.fail(f"{int(wrong[~edge].sum())} interior and {int(wrong[edge].sum())} of "
                    f"{int(edge.sum())} edge mismatches; masks in {where}")
    wall_px = want["coverage"] & ~want["box"] & ~edge & _wall_pixels(scene)
    assert wall_px.sum() >= 30 and not lit[0][wall_px].any()
    assert want["floor_shadow"][~edge].sum() >= 30


def test_pyrender_shadow_maps_ignore_faces_wound_away_from_the_light():
    # pyrender's shadow pass culls back faces even for double-sided materials, so the same wall
    # wound toward the camera casts no shadow in pyrender: its masks call the wall's shadow lit.
    # This is pyrender's behaviour, shown so that compare's numbers can be read; the interior of
    # the wall's shadow (beside the box's) must come out lit.
    scene = _wall_sun_scene(wall_winding=1.0)
    want = _expected_masks(scene, wall=True)
    lit, _ = pb.pyrender_shadow_masks(scene)
    box_only = _expected_masks(scene.replace(objects=scene.objects[:2]))
    wall_shadow = want["floor_shadow"] & ~box_only["floor_shadow"] & ~_wall_pixels(scene)
    wall_shadow &= ~_edges(want["lit"], want["coverage"], box_only["lit"])
    assert wall_shadow.sum() >= 10 and lit[0][wall_shadow].all()


def _wall_pixels(scene):
    o, d = _pixel_rays(scene)
    hw, tw = _hit_wall(o, d)
    hb, tb, _ = _hit_box(o, d)
    return hw & ~(hb & (tb < tw))


def test_pyrender_leaves_a_moderngl_context_usable():
    # pyrender's own teardown eglTerminates the shared EGL display (pyrender#223) and leaves its
    # context current; the bridge must leave the caller's moderngl context current and alive,
    # render after render.
    from shadowvol.raster.platform.context import create_context
    ctx = create_context()
    try:
        fbo = ctx.simple_framebuffer((4, 4))
        fbo.use()
        scene = _light_box_scene(width=16, height=12)
        for colour in ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)):
            pb.render_pyrender(scene)
            fbo.clear(*colour, 1.0)
            pixels = np.frombuffer(fbo.read(components=3), np.uint8).reshape(4, 4, 3)
            assert (pixels == np.array(colour, np.uint8) * 255).all()
            assert ctx.error == "GL_NO_ERROR"
        fbo.release()
    finally:
        ctx.release()
