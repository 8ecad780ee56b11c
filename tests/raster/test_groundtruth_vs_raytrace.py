"""The rasterizer's ground truth (`Renderer.render(outputs=...)`, shadowvol.raster.truth.truth_pass)
against the ray tracer's (raytrace.ground_truth), pixel by pixel, on every scene file and on
built cases.

Budgets: object_id, facing, cast and every bit of casters: zero mismatches farther than one
pixel from an edge of either renderer's mask of that quantity or of the object ids
(shadowvol.compare.maskdiff.edge_pixels), and under 0.1% of the pixels in all.  depth and
distance: within RASTER_DEPTH_RTOL where both hit the same object away from its edges.
normals: equal where both see the same facet (the same object, and a normal constant over the
3 x 3 neighbourhood in both).  On the raster side cast == casters.any(-1) exactly, and asking for
the ground truth never changes lit.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from builders import (
    MODELS,
    SCENES,
    TEST_OUTPUT,
    cards_scene,
    check_counts,
    check_facing_counts,
)
from hypothesis import given, settings
from strategies import profile
from strategies import scenes as random_scenes

from raytrace.groundtruth import ground_truth
from shadowvol.compare.maskdiff import edge_pixels
from shadowvol.frame import decode_casters
from shadowvol.io import save_png
from shadowvol.pictures import ground_truth_picture
from shadowvol.primitives import box, mesh, plane, sphere
from shadowvol.raster.truth import truth_pass
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import (
    AreaLight,
    Camera,
    DirectionalLight,
    PointLight,
    Scene,
    SpotLight,
)
from shadowvol.scenefile import load_scene, save_scene

ALL = ("image", "lit", "coverage", "depth", "distance", "normal", "object_id", "facing",
       "facing_count", "casters")
# Both meet the pixel's ray with the visible triangle's float32 plane in float64 (within ~6e-7
# of each other where both see the same triangle); where they see the same object through
# neighbouring triangles (a tie near their shared edge) the planes differ.  3e-5 allowed, as
# CONVENTIONS says.
RASTER_DEPTH_RTOL = 3e-5
MAX_MISMATCH_FRACTION = 0.001
SIZE = dict(width=160, height=120)


def built_cases() -> dict[str, Scene]:
    spot = SpotLight([0.5, 4.0, 1.5], [-0.1, -1.0, -0.3], 35.0)
    balls = [sphere(f"ball{i}", [x, 0.5 + 0.3 * i, z], 0.35, subdivisions=2)
             for i, (x, z) in enumerate([(-1.2, 0.0), (-0.4, 0.3), (0.4, -0.2), (1.1, 0.4)])]
    row = Scene(camera=Camera(eye=[0.5, 3.0, 5.0], target=[0.0, 0.4, 0.0], fov_y=45.0),
                objects=[plane("floor", size=[8, 8])] + balls
                + [box("wall", [0.0, 1.0, -1.5], [4.0, 2.0, 0.1])],
                lights=[PointLight([2.0, 4.0, 2.0]), DirectionalLight([-0.6, -1.0, -0.3]), spot],
                **SIZE)
    return {"cards, straight down": cards_scene(**SIZE),
            "cards, point light": cards_scene(light=PointLight([0.8, 4.0, 0.4]), **SIZE),
            "cards, spot": cards_scene(light=spot, **SIZE),
            "balls and a wall, three lights": row}


CASES = {**{p.stem: None for p in sorted(SCENES.glob("*.toml"))}, **built_cases()}


def case(name: str) -> Scene:
    scene = CASES[name]
    return load_scene(SCENES / f"{name}.toml").replace(**SIZE) if scene is None else scene


def near_id_edges(a: np.ndarray, b: np.ndarray, objects: int) -> np.ndarray:
    return np.logical_or.reduce([edge_pixels(a == k) | edge_pixels(b == k)
                                 for k in range(objects + 1)])


def flat_normal(normal: np.ndarray) -> np.ndarray:
    """(H, W) bool: the normal is the same over the pixel's 3 x 3 neighbourhood."""
    p = np.pad(normal, ((1, 1), (1, 1), (0, 0)), mode="edge")
    h, w = normal.shape[:2]
    return np.logical_and.reduce([(p[dy:dy + h, dx:dx + w] == normal).all(axis=-1)
                                  for dy in range(3) for dx in range(3)])


def compare(request, scene: Scene, raster, ref) -> list[str]:
    """Every budget of the module; returns the failures (empty when all hold).  On failure
    both pictures and the ids' difference go under test-output/<test>/."""
    failures = []
    n = len(scene.objects)
    ids = near_id_edges(raster.object_id, ref.object_id, n)
    limit = MAX_MISMATCH_FRACTION * ids.size

    def masks(label, got, want, either=None):
        """`either` (H, W) bool: pixels where both answers are right (not counted)."""
        near = ids | edge_pixels(got) | edge_pixels(want)
        bad = (got != want) if either is None else (got != want) & ~either
        if (bad & ~near).any() or bad.sum() > max(limit, 4):
            failures.append(f"{label}: {int(bad.sum())} differ, {int((bad & ~near).sum())} "
                            f"off the edges: {np.argwhere(bad & ~near)[:4].tolist()}")

    masks("coverage", raster.coverage, ref.coverage)
    # coincident surfaces of two objects (a random scene may hold a mesh twice): which one is
    # seen is a tie, undecided by CONVENTIONS; where the ids differ but the depths agree, either
    with np.errstate(invalid="ignore"):
        tie = (raster.coverage & ref.coverage & (raster.object_id != ref.object_id)
               & (np.abs(raster.depth / ref.depth - 1) <= RASTER_DEPTH_RTOL))
    for k in range(n + 1):
        masks(f"object_id == {k}", raster.object_id == k, ref.object_id == k, tie)
    for i in range(len(scene.lights)):
        masks(f"light {i} lit", raster.lit[i], ref.lit[i])
        masks(f"light {i} facing", raster.facing[i], ref.facing[i])
        masks(f"light {i} cast", raster.cast[i], ref.cast[i])
        got_bits = decode_casters(raster.casters[i], n)
        want_bits = decode_casters(ref.casters[i], n)
        for j in range(n):
            masks(f"light {i} casters bit {j}", got_bits[..., j], want_bits[..., j])
    if not np.array_equal(raster.cast, raster.casters.any(-1)):
        failures.append("raster: cast != casters.any(-1)")
    for who, frame in (("raster", raster), ("raytrace", ref)):
        if not np.array_equal(frame.casters.any(-1), frame.lit_count < frame.facing_count):
            failures.append(f"{who}: casters.any(-1) != (lit_count < facing_count)")
    same = (raster.object_id == ref.object_id) & ref.coverage & ~ids
    for name in ("depth", "distance"):
        got, want = getattr(raster, name)[same], getattr(ref, name)[same]
        worst = float(np.max(np.abs(got / want - 1))) if same.any() else 0.0
        if worst > RASTER_DEPTH_RTOL:
            failures.append(f"{name}: relative difference up to {worst:.2e}")
    facet = same & flat_normal(raster.normal) & flat_normal(ref.normal)
    unequal = facet & ~(raster.normal == ref.normal).all(axis=-1)
    if unequal.any():
        failures.append(f"normals differ on {int(unequal.sum())} pixels of one facet: "
                        f"{np.argwhere(unequal)[:4].tolist()}")
    if failures:
        out = TEST_OUTPUT / re.sub(r"[^A-Za-z0-9_.-]+", "_", request.node.name)
        names = [o.name for o in scene.objects]
        save_png(out / "raster.png", ground_truth_picture(raster, names))
        save_png(out / "raytrace.png", ground_truth_picture(ref, names))
    return failures


@pytest.fixture(scope="module")
def renderer_for(gl_session):
    """renderer_for(scene) -> a Renderer on the session's context (released at the end)."""
    made = []

    def make(scene):
        made.append(Renderer(scene, gl_session))
        return made[-1]
    yield make
    for r in made:
        r.release()


@pytest.mark.parametrize("name", list(CASES))
def test_raster_ground_truth_matches_the_ray_tracer(ctx, renderer_for, request, name):
    scene = case(name)
    r = renderer_for(scene)
    raster = r.render(outputs=ALL)
    plain = r.render()
    np.testing.assert_array_equal(raster.lit, plain.lit)  # the ground truth changes nothing
    np.testing.assert_array_equal(raster.image, plain.image)
    ref = ground_truth(scene)
    failures = compare(request, scene, raster, ref)
    assert not failures, failures
    if any(isinstance(light, AreaLight) for light in scene.lights):
        # an area light's counts, under the counts' budget (tests/builders.py)
        check_counts(scene, raster, ref)
        check_facing_counts(scene, raster, ref)
    # the case tests something: shadows where the scene has lights
    assert raster.cast.any() or not scene.lights
    for name_, value in ref.calibration.arrays().items():
        np.testing.assert_array_equal(raster.calibration.arrays()[name_], value)


def test_zfail_and_gpu_silhouettes_give_the_same_casters(ctx, renderer_for):
    scene = load_scene(SCENES / "stack.toml").replace(**SIZE)
    r = renderer_for(scene)
    base = r.render(outputs=ALL)
    for method, silhouettes in (("zfail", "cpu"), ("auto", "gpu")):
        other = r.render(method, silhouettes, outputs=ALL)
        for name in ("casters", "facing", "object_id", "depth", "normal"):
            np.testing.assert_array_equal(getattr(other, name), getattr(base, name),
                                          err_msg=f"{method}/{silhouettes}: {name}")


def test_real_mesh_ground_truth_matches(ctx, renderer_for, request):
    if not MODELS.is_dir():
        pytest.skip(f"the shared test meshes are missing: {MODELS} does not exist")
    import trimesh

    loaded = trimesh.load(str(MODELS / "spot.obj"), process=False)
    v = np.asarray(loaded.vertices, np.float64)
    v = (v - v.mean(axis=0)) * (1.5 / np.ptp(v, axis=0).max())
    v[:, 1] -= v[:, 1].min()
    scene = Scene(camera=Camera(eye=[0.6, 1.6, 2.6], target=[0.0, 0.6, 0.0]),
                  objects=[plane("floor", size=[6, 6]), mesh("spot", v, loaded.faces),
                           box("block", [0.9, 0.25, 0.6], [0.4, 0.5, 0.4])],
                  lights=[PointLight([1.5, 3.5, 1.0]), DirectionalLight([-0.4, -1.0, -0.3])],
                  **SIZE)
    r = renderer_for(scene)
    failures = compare(request, scene, r.render(outputs=ALL), ground_truth(scene))
    assert not failures, failures


def test_only_the_outputs_asked_for(ctx, renderer_for):
    scene = cards_scene(32, 24)
    frame = renderer_for(scene).render(outputs=("depth", "object_id"))
    assert frame.normal is None and frame.casters is None and frame.image is None
    assert frame.depth.dtype == np.float32 and frame.object_id.dtype == np.uint16
    assert set(frame.arrays()) == {"depth", "object_id", "K", "world_to_camera",
                                   "camera_to_world", "light_position", "light_direction"}


def test_more_than_64_objects_have_casters_in_two_words(ctx, gl_session, request):
    cubes = [box(f"c{i}", [i % 9 - 4.0, 0.2, i // 9 - 4.0], [0.3, 0.3, 0.3]) for i in range(70)]
    scene = Scene(camera=Camera(eye=[0, 8, 8], target=[0, 0, 0]),
                  objects=cubes + [plane("floor", point=(0, 0.05, 0))],
                  lights=[DirectionalLight([0.3, -1, 0.2])], width=32, height=24)
    with Renderer(scene, gl_session) as r:
        raster = r.render(outputs=ALL)
    assert raster.object_id.max() > 64
    assert raster.casters.shape == (1, 24, 32, 2) and raster.casters[..., 1].any()
    assert not compare(request, scene, raster, ground_truth(scene))


def test_casters_count_only_objects_near_the_shadow(ctx, gl_session, monkeypatch):
    """30 balls far from the one shadow are not counted: one counting pass over the
    candidates, the ball and the floor the shadow falls on (its box holds the shadow: it could
    cast there)."""
    far = [sphere(f"far{i}", [-30.0 + 2 * i, 0.5, -40.0], 0.4, subdivisions=1) for i in range(30)]
    scene = Scene(camera=Camera(eye=[0, 3, 5], target=[0, 0.3, 0], fov_y=40.0),
                  objects=[plane("floor", size=[6, 6]), sphere("ball", [0, 0.8, 0], 0.4)] + far,
                  lights=[PointLight([0.5, 4.0, 0.5])], width=64, height=48)
    counted = []
    original = truth_pass.passes.count_each_caster

    def spy(*args, objects=None, **kwargs):
        if objects is not None:
            counted.append(tuple(objects))
        return original(*args, objects=objects, **kwargs)

    monkeypatch.setattr(truth_pass.passes, "count_each_caster", spy)
    with Renderer(scene, gl_session) as r:
        frame = r.render(outputs=("casters",))
    assert counted == [(0, 1)]
    assert (frame.casters[0, ..., 0] == 2).sum() > 20 and set(np.unique(frame.casters)) == {0, 2}


def test_candidates_are_conservative_and_few():
    bounds = np.array([[[-1, 0, -1], [1, 1, 1]], [[5, 0, 5], [6, 1, 6]],
                       [[-1, 2, -1], [1, 3, 1]]], float)
    points = np.array([[0.0, 0.0, 0.0], [0.5, 0.0, 0.5]])
    assert truth_pass.caster_candidates(bounds, points, np.array([0, 5.0, 0, 1])) == [0, 2]
    # a directional light from +x: only what lies toward +x of the points
    assert truth_pass.caster_candidates(bounds, points, np.array([1.0, 0.0, 0.0, 0.0])) == [0]
    assert truth_pass.caster_candidates(bounds, points, np.array([1.0, 0.0, 1.0, 0.0])) == [0, 1]


@settings(profile(), max_examples=25, deadline=None)
@given(scene=random_scenes())
def test_random_scenes_ground_truth_matches(ctx, request, scene):
    """The property tests' random scenes (tests/strategies.py): soups, closed meshes, cameras
    anywhere, 1-3 lights of every kind; the same budgets.  A failure is saved as a scene file
    under test-output/robustness/ (any command renders it)."""
    with Renderer(scene, ctx) as r:
        raster = r.render(outputs=ALL)
    failures = compare(request, scene, raster, ground_truth(scene))
    if failures:
        path = TEST_OUTPUT / "robustness" / "failing-groundtruth.json"
        save_scene(scene, path)
        raise AssertionError(f"{failures}; the scene is saved as {path}")


def test_casters_past_the_first_16_bits(ctx, gl_session, request):
    """64 objects, the casters at indices 17, 38 and 63 (the raster sums 16 bits a channel):
    every bit where the ray tracer has it."""
    objects = [plane("floor", size=[8, 8])]
    objects += [box(f"far{i}", [20.0 + i, 0.2, -30.0], [0.3, 0.3, 0.3]) for i in range(63)]
    for k, (x, z) in zip((17, 38, 63), [(-0.8, 0.0), (0.3, 0.4), (0.9, -0.5)]):
        objects[k] = box(f"caster{k}", [x, 0.9, z], [0.6, 0.1, 0.6])
    scene = Scene(camera=Camera(eye=[0.0, 3.5, 4.0], target=[0.0, 0.3, 0.0], fov_y=45.0),
                  objects=objects, lights=[PointLight([0.2, 4.0, 0.3])], **SIZE)
    with Renderer(scene, gl_session) as r:
        raster = r.render(outputs=ALL)
    ref = ground_truth(scene)
    assert not compare(request, scene, raster, ref)
    for k in (17, 38, 63):
        assert ((raster.casters[0, ..., 0] >> np.uint64(k)) & np.uint64(1)).sum() > 50, k


def test_more_candidates_than_one_counting_pass(ctx, gl_session, request):
    """40 boxes casting on the floor and on each other: more candidates than one counting
    pass holds (truth_pass.CASTERS_PER_GROUP), so two groups add their bits to the same mask."""
    boxes = [box(f"b{k}", [0.55 * (k % 8) - 1.9, 0.3 + 0.25 * (k // 8), 0.5 * (k // 8) - 1.0],
                 [0.3, 0.12, 0.3]) for k in range(40)]
    scene = Scene(camera=Camera(eye=[0.0, 4.0, 4.5], target=[0.0, 0.3, 0.0], fov_y=50.0),
                  objects=[plane("floor", size=[8, 8])] + boxes,
                  lights=[PointLight([0.4, 5.0, 1.0])], **SIZE)
    assert len(scene.objects) > truth_pass.CASTERS_PER_GROUP
    with Renderer(scene, gl_session) as r:
        raster = r.render(outputs=ALL)
    ref = ground_truth(scene)
    assert not compare(request, scene, raster, ref)
    seen = np.bitwise_or.reduce(raster.casters[0, ..., 0].reshape(-1))
    assert bin(int(seen)).count("1") > truth_pass.CASTERS_PER_GROUP


def test_a_second_frame_keeps_nothing_of_the_first(ctx, gl_session):
    """The G-buffer is written only where geometry is: a frame that sees less (the camera
    turned away) must not show the first frame's surfaces where it sees nothing."""
    scene = load_scene(SCENES / "stack.toml").replace(**SIZE)
    away = Camera(eye=scene.camera.eye, target=scene.camera.eye + np.array([-1.0, 0.3, -1.0]),
                  fov_y=scene.camera.fov_y)
    with Renderer(scene, gl_session) as r:
        r.render(outputs=ALL)
        second = r.render(camera=away, outputs=ALL)
    with Renderer(scene.replace(camera=away), gl_session) as fresh:
        alone = fresh.render(outputs=ALL)
    assert (~alone.coverage).any()
    for name in ("depth", "normal", "object_id", "facing", "casters", "lit"):
        np.testing.assert_array_equal(getattr(second, name), getattr(alone, name),
                                      err_msg=name)
