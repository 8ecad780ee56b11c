"""Planar projected shadows in GL (shadowvol.raster.planar.draw): right where the answer is known,
and wrong exactly where the method is known to be wrong."""

from __future__ import annotations

import numpy as np
import pytest
from builders import SCENES

import raytrace
from raytrace.backends import make_backend
from raytrace.camera import primary_rays
from shadowvol.compare.maskdiff import edge_pixels
from shadowvol.raster.planar.matrix import project_points, projection_matrix
from shadowvol.primitives import Transform, box, plane, sphere
from shadowvol.raster import stencil as stencil_gl
from shadowvol.raster.planar.draw import (
    PlanarShadows,
    ReceiverError,
    receiver_index,
    receiver_plane,
)
from shadowvol.raster.projection import view_projection
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import Camera, DirectionalLight, Material, PointLight, Scene
from shadowvol.scenefile import load_scene

FOLDER_GL = False  # only the tests that take `ctx` render (conftest.py)

FLOOR = Material(ambient=[0.5, 0.5, 0.5], diffuse=[0.8, 0.8, 0.8], specular=[0, 0, 0])
BLOCK = Material(ambient=[0.2, 0.3, 0.5], diffuse=[0.3, 0.5, 0.8], specular=[0, 0, 0])


def box_over_floor(light) -> Scene:
    """A rotated box floating over a 10 x 10 floor (convex: its only self-shadow is n . l)."""
    return Scene(
        camera=Camera(eye=[1.8, 2.8, 3.4], target=[-0.3, 0.4, -0.2], fov_y=45.0),
        objects=(plane("floor", size=(10.0, 10.0), material=FLOOR),
                 box("box", center=(0.0, 0.0, 0.0), size=(1.2, 0.6, 0.8), material=BLOCK,
                     transform=Transform(rotation=(0.0, 35.0, 0.0),
                                                   translation=(-0.2, 1.1, 0.1)))),
        lights=(light,), width=160, height=120, ambient=[0.2, 0.2, 0.2], name="box_over_floor")


def object_ids(scene: Scene) -> np.ndarray:
    """(H, W) int: the object visible at each pixel centre (-1: none), by the ray tracer."""
    vertices, faces, ids = scene.triangles()
    tracer = make_backend("embree", vertices, faces)
    o, d = primary_rays(scene.camera, scene.width, scene.height)
    tri = tracer.closest_hit(o, d).tri
    return np.where(tri >= 0, ids[tri], -1).reshape(scene.height, scene.width)


@pytest.mark.parametrize("light", [PointLight(position=[1.5, 5.0, 1.0]),
                                   DirectionalLight(direction=[-0.4, -1.0, -0.3])],
                         ids=["point", "directional"])
def test_box_over_floor_matches_the_ray_tracer(ctx, assert_masks_match, light):
    # A convex box over a floor is the one case projected shadows get entirely right: the
    # floor's shadow is the box's projection, and the box shadows nothing else.
    scene = box_over_floor(light)
    with Renderer(scene, ctx) as r, PlanarShadows(r) as planar:
        got = planar.render(stencil=True)
    ref_lit, ref_cov = raytrace.shadow_masks(scene)
    assert got.receiver == 0
    on_floor = object_ids(scene) == 0
    shadow = on_floor & ~ref_lit[0]
    assert shadow.sum() > 300, "the test needs a real shadow on the floor"
    assert_masks_match(got, ref_lit, ref_cov)
    # every projected-shadow pixel is a ray-traced floor shadow pixel, up to the edge budget
    marked = got.stencil[0] == stencil_gl.PLANAR_SHADOW
    assert (marked & ~shadow).sum() <= 0.001 * marked.size


def test_shadow_on_another_object_is_missing(ctx):
    # scenes/planar.toml: the ball's shadow falls on the box.  Shadow volumes draw it; the
    # projection onto the floor cannot.
    scene = load_scene(SCENES / "planar.toml")
    names = [o.name for o in scene.objects]
    ids = object_ids(scene)
    on_box = ids == names.index("box")
    without_ball = scene.replace(objects=tuple(o for o in scene.objects if o.name != "ball"))
    with Renderer(scene, ctx) as r, PlanarShadows(r) as planar:
        volumes = r.render()
        projected = planar.render(stencil=True)
    with Renderer(without_ball, ctx) as r:
        no_ball = r.render()
    # the ball's shadow on the box: shadowed with the ball, lit without it (shadow volumes)
    ball_shadow_on_box = on_box & ~volumes.lit[0] & no_ball.lit[0]
    assert ball_shadow_on_box.sum() > 2000
    # projected shadows light every one of those pixels
    assert projected.lit[0][ball_shadow_on_box].all()
    # and off the floor they never shadow anything: off-floor lit = n . l alone, on every
    # pixel where the raster's receiver mark is not set, and on every pixel the ray tracer
    # sees another object on, but for the floor's outline (within one pixel of it, the two
    # may see a different surface at a pixel centre)
    with Renderer(scene, ctx) as r:
        unshadowed = r.render(shadows=False)
    off_mark = projected.coverage & (projected.stencil[0] == 0)
    off_floor = (projected.coverage & (ids != projected.receiver)
                 & ~edge_pixels(ids == projected.receiver))
    for off in (off_mark, off_floor):
        assert off.sum() > 0.05 * off.size                  # the box, the ball, the cage
        assert np.array_equal(projected.lit[0][off], unshadowed.lit[0][off])


def test_the_example_shows_its_floor_shadows(ctx):
    """scenes/planar.toml, as `shadowvol planar` draws it: the light stands low and to the
    side, so the projected shadows reach out from under their casters and cover a clear part
    of the floor the camera sees (at least 8 % of it; the old light above the camera's
    shoulder hid them behind the objects, 0.4 %), every caster's shadow reaching past it."""
    scene = load_scene(SCENES / "planar.toml")
    with Renderer(scene, ctx) as r, PlanarShadows(r) as planar:
        got = planar.render(stencil=True)
    marked = got.stencil[0] == stencil_gl.PLANAR_SHADOW
    floor = marked | (got.stencil[0] == stencil_gl.PLANAR_RECEIVER)
    assert marked.sum() >= 0.08 * floor.sum()
    ids = object_ids(scene)
    names = [o.name for o in scene.objects]
    for caster in ("box", "cage"):   # its shadow shows beside it, in the columns it covers
        cols = np.flatnonzero((ids == names.index(caster)).any(axis=0))
        beside = marked[:, cols.max() + 1:cols.max() + 40]
        assert beside.sum() > 200, caster


def test_self_shadowing_is_missing(ctx):
    # The cage of scenes/planar.toml shadows its own inside through its windows (shadow
    # volumes); projected onto the floor, it shadows nothing of itself.
    scene = load_scene(SCENES / "planar.toml")
    on_cage = object_ids(scene) == [o.name for o in scene.objects].index("cage")
    with Renderer(scene, ctx) as r, PlanarShadows(r) as planar:
        volumes = r.render()
        projected = planar.render()
        unshadowed = r.render(shadows=False)
    self_shadow = on_cage & unshadowed.lit[0] & ~volumes.lit[0]
    assert self_shadow.sum() > 100
    assert projected.lit[0][self_shadow].all()


def test_overlapping_shadows_darken_once(ctx):
    # Two boxes whose floor shadows overlap, and each closed box projects front and back
    # triangles onto the same pixels: the stencil lets each floor pixel be shadowed once, so
    # the overlap is exactly as dark as a single shadow.  The floor is lit uniformly (a
    # directional light, no specular) so every shadowed floor pixel has the same value.
    light = DirectionalLight(direction=[-0.3, -1.0, -0.2])
    scene = box_over_floor(light)
    second = box("box 2", center=(0.0, 0.0, 0.0), size=(0.8, 0.5, 0.8), material=BLOCK,
                 transform=Transform(translation=(0.6, 1.8, 0.5)))
    scene = scene.replace(objects=scene.objects + (second,))
    one = scene.replace(objects=scene.objects[:2])
    two = scene.replace(objects=(scene.objects[0], second))
    with Renderer(scene, ctx) as r, PlanarShadows(r) as planar:
        both = planar.render(stencil=True)
    shadows = []
    for s in (one, two):
        with Renderer(s, ctx) as r, PlanarShadows(r) as planar:
            res = planar.render(stencil=True)
        shadows.append(res.stencil[0] == stencil_gl.PLANAR_SHADOW)
    on_floor = object_ids(scene) == 0
    overlap = shadows[0] & shadows[1] & on_floor
    single = (shadows[0] ^ shadows[1]) & on_floor
    assert overlap.sum() > 100 and single.sum() > 100, "the shadows must overlap in part"
    shade = both.image[overlap]
    assert np.ptp(shade, axis=0).max() < 1e-6, "the overlap is not uniformly shaded"
    assert np.abs(both.image[single] - shade[0]).max() < 1e-6
    lit_floor = on_floor & both.lit[0]
    assert (both.image[lit_floor] > shade[0] + 0.1).all()  # and a shadow is darker than lit


def test_no_shadow_off_the_receivers_edge(ctx):
    # A small table under a box, a big ground one unit below: part of the box's projection onto
    # the table's plane lies beyond the table and in front of the ground, where the classic
    # bug draws it "hanging in the air".  The stencil mark keeps it on the table.
    light = PointLight(position=[-2.5, 5.0, 0.5])
    ground = plane("ground", point=(0.0, -1.0, 0.0), size=(20.0, 20.0), material=FLOOR)
    table = plane("table", size=(2.0, 2.0), material=FLOOR)
    block = box("box", center=(0.2, 1.0, 0.0), size=(0.8, 0.4, 0.8), material=BLOCK)
    scene = Scene(camera=Camera(eye=[1.5, 5.0, 6.0], target=[0.5, 0.0, 0.0]),
                  objects=(ground, table, block), lights=(light,), width=160, height=120,
                  ambient=[0.2, 0.2, 0.2])
    # precondition: the projection reaches past the table's edge x = 1, inside the picture
    corners = block.vertices
    m = projection_matrix([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], light)
    flat = project_points(m, corners)
    assert flat[:, 0].max() > 1.3
    beyond = flat[flat[:, 0] > 1.0]
    clip = np.c_[beyond, np.ones(len(beyond))] @ view_projection(scene.camera, scene.size).T
    assert (np.abs(clip[:, :2] / clip[:, 3:]) < 1).all()
    with Renderer(scene, ctx) as r, PlanarShadows(r) as planar:
        got = planar.render("table", stencil=True)
        unshadowed = r.render(shadows=False)
    ids = object_ids(scene)
    marked = got.stencil[0] == stencil_gl.PLANAR_SHADOW
    assert marked.sum() > 100 and (ids[marked] == 1).all()
    not_table = got.coverage & (ids != 1)
    assert np.array_equal(got.lit[0][not_table], unshadowed.lit[0][not_table])


def test_anti_shadows_are_not_drawn(ctx):
    # A box ABOVE the point light (nothing between light and floor) and a box below the floor:
    # both project onto the floor (through the light, or upward) and neither may shadow it.
    light = PointLight(position=[0.0, 2.0, 0.0])
    objects = (plane("floor", size=(10.0, 10.0), material=FLOOR),
               box("above", center=(0.5, 3.0, 0.3), size=(0.8, 0.4, 0.8), material=BLOCK),
               box("below", center=(-0.8, -1.0, 0.5), size=(0.8, 0.4, 0.8), material=BLOCK))
    scene = Scene(camera=Camera(eye=[0.0, 6.0, 7.0], target=[0.0, 0.0, 0.0]), objects=objects,
                  lights=(light,), width=120, height=90, ambient=[0.2, 0.2, 0.2])
    with Renderer(scene, ctx) as r, PlanarShadows(r) as planar:
        got = planar.render(stencil=True)
    assert not (got.stencil[0] == stencil_gl.PLANAR_SHADOW).any()
    # the projections do land on the visible floor: drop the anti-shadow test by moving the
    # light above both boxes, and the "above" box shadows it
    high = scene.replace(lights=(PointLight(position=[0.0, 8.0, 0.0]),))
    with Renderer(high, ctx) as r, PlanarShadows(r) as planar:
        assert (planar.render(stencil=True).stencil[0] == stencil_gl.PLANAR_SHADOW).sum() > 50


def test_receiver_choice():
    scene = load_scene(SCENES / "planar.toml")
    assert receiver_index(scene) == 0                      # the floor: the only plane
    assert receiver_index(scene, "box") == 1
    assert np.allclose(receiver_plane(scene, 0), [0.0, 1.0, 0.0, 0.0])
    with pytest.raises(ReceiverError, match="not flat"):
        receiver_plane(scene, receiver_index(scene, "box"))
    with pytest.raises(ReceiverError, match="no object named"):
        receiver_index(scene, "nothing")
    walls = load_scene(SCENES / "cage.toml")
    assert walls.objects[receiver_index(walls)].name == "floor"   # 9 x 9 beats 9 x 5
    no_plane = scene.replace(objects=(sphere("ball", [0.0, 1.0, 0.0], 0.5),))
    with pytest.raises(ReceiverError, match="no plane object"):
        receiver_index(no_plane)
