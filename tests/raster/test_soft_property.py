"""Random scenes (tests/strategies.py) with their point and spot lights made area lights (rect,
disk, sphere; N in {1, 4, 16}): raster and ray-traced counts equal off every sample edge."""

from __future__ import annotations

import numpy as np
from builders import TEST_OUTPUT, check_counts
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from strategies import PROFILE, coord, direction, profile, rounding_tie, scenes

import raytrace
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import AreaLight, DirectionalLight, hard_lights
from shadowvol.scenefile import save_scene


@st.composite
def area_scenes(draw):
    scene = draw(scenes())
    lights = []
    for light in scene.lights:
        if isinstance(light, DirectionalLight):
            lights.append(light)
            continue
        shape = draw(st.sampled_from(["rect", "disk", "sphere"]))
        args = dict(center=light.position, samples=draw(st.sampled_from([1, 4, 16])),
                    pattern=draw(st.sampled_from(["stratified", "halton"])),
                    seed=draw(st.integers(0, 9)))
        if shape != "sphere":
            args["normal"] = draw(direction())
        if shape == "rect":
            args["size"] = [draw(coord(0.0625, 1.0)), draw(coord(0.0625, 1.0))]
        else:
            args["radius"] = draw(coord(0.0625, 0.5))
        lights.append(AreaLight(shape, **args))
    scene = scene.replace(lights=tuple(lights))
    hard = scene.replace(lights=tuple(h for lt in scene.lights for h in hard_lights(lt)))
    # a sample in a face's plane up to rounding decides n·l by the last bit (see rounding_tie)
    assume(not rounding_tie(hard))
    assume(_clearance(hard) >= CLEARANCE)
    return scene


# Samples closer than this to a surface are left out.  Seen from a light a little above a
# surface, an object standing on that surface casts a contact shadow whose height above the
# surface is, near the contact, thinner than the masks' margin there (`raytrace.tolerances`:
# "a contact shadow thinner than eps is lost"), over a band about eps * distance / height wide:
# at 0.003 above a floor that band is pixels wide and the ray tracer lights it, the raster does
# not.  Hard lights are drawn on a grid of sixteenths and rarely come this close.
CLEARANCE = 1 / 32


def _clearance(scene) -> float:
    """The smallest distance from a point or spot light of `scene` to any of its triangles."""
    from trimesh.triangles import closest_point

    points = [lt.position for lt in scene.lights if not isinstance(lt, DirectionalLight)]
    if not points:
        return np.inf
    vertices, faces, _ = scene.triangles()
    triangles = vertices[faces]
    pts = np.repeat(np.array(points), len(triangles), axis=0)
    tris = np.tile(triangles, (len(points), 1, 1))
    return float(np.linalg.norm(closest_point(tris, pts) - pts, axis=1).min())


# ci: 20 scenes (each has up to 3 x 16 samples); the long profile takes its own number
@settings(profile(), max_examples=20 if PROFILE == "ci" else profile().max_examples)
@given(scene=area_scenes())
def test_random_area_light_scenes(ctx, scene):
    ref = raytrace.soft_masks(scene)
    with Renderer(scene, ctx) as r:
        for method in ("auto", "zfail"):
            try:
                check_counts(scene, r.render(method), ref)
            except AssertionError:
                out = TEST_OUTPUT / "test_random_area_light_scenes" / "scene.json"
                save_scene(scene, out)  # the failing scene, to load and look at
                raise AssertionError(f"{method}: counts differ; the scene is in {out}") from None
