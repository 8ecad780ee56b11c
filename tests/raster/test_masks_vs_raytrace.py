"""The rasterizer's masks against the ray tracer's (raytrace.shadow_masks), pixel by pixel.

Budget (conftest.assert_masks_match): zero mismatches farther than one pixel from a mask edge,
fewer than 0.1% in total.  Every scene in scenes/ is checked (a glob, so new scenes are covered),
plus scenes built here for the classic failure modes of shadow volumes.
"""

from __future__ import annotations

import numpy as np
import pytest
from builders import ROOT

import raytrace
from shadowvol.primitives import Transform, box, mesh, plane, sphere
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import (
    Camera,
    DirectionalLight,
    Material,
    PointLight,
    Scene,
    SpotLight,
)
from shadowvol.scenefile import load_scene

SCENE_FILES = sorted(p for p in (ROOT / "scenes").iterdir() if p.suffix in (".toml", ".json"))
SIZE = dict(width=128, height=96)
RUNS = [("auto", "cpu"), ("auto", "gpu"), ("zfail", "cpu"), ("zfail", "gpu")]


def test_there_are_scene_files():
    assert len(SCENE_FILES) >= 1


@pytest.fixture(scope="module")
def reference():
    """reference(scene) -> (lit, coverage), each scene traced once per module."""
    cache = {}

    def get(key: str, scene: Scene):
        if key not in cache:
            cache[key] = raytrace.shadow_masks(scene)
        return cache[key]

    return get


@pytest.mark.parametrize("path", SCENE_FILES, ids=lambda p: p.name)
def test_scene_files(ctx, reference, assert_masks_match, path):
    scene = load_scene(path).replace(**SIZE)
    ref_lit, ref_cov = reference(path.name, scene)
    with Renderer(scene, ctx) as r:
        results = {run: r.render(*run) for run in RUNS}
    for (method, silhouettes), res in results.items():
        assert_masks_match(res, ref_lit, ref_cov, f"{method}-{silhouettes}")
    np.testing.assert_array_equal(results["auto", "cpu"].lit, results["auto", "gpu"].lit)


# ---- built cases ------------------------------------------------------------------------------

FLOOR = Material(ambient=[0.5, 0.5, 0.45], diffuse=[0.8, 0.8, 0.7], specular=[0, 0, 0])
RED = Material(ambient=[0.4, 0.1, 0.1], diffuse=[0.8, 0.2, 0.2])


def _floor(size=12.0):
    return plane("floor", size=[size, size], material=FLOOR)


def _scene(objects, lights, eye=(0.0, 3.0, 6.0), target=(0.0, 0.5, 0.0), near=0.05, fov=50.0):
    return Scene(camera=Camera(eye=list(eye), target=list(target), fov_y=fov, near=near),
                 objects=objects, lights=lights, **SIZE)


def _soup(obj, name):
    """The same triangles with every corner its own vertex (all seams duplicated)."""
    tri = obj.triangles.reshape(-1, 3)
    return mesh(name, tri, np.arange(len(tri)).reshape(-1, 3), obj.material)


def _flip_some(obj, name, seed=1):
    """Reverse the winding of a random half of the triangles."""
    rng = np.random.default_rng(seed)
    faces = obj.faces.copy()
    flip = rng.random(len(faces)) < 0.5
    faces[flip] = faces[flip][:, ::-1]
    return mesh(name, obj.vertices, faces, obj.material)


def _fan():
    """Three triangles on one edge (a non-manifold edge), wound every which way."""
    a, b = [-0.6, 1.2, 0.0], [0.6, 1.2, 0.0]
    v = np.array([a, b, [0.0, 1.9, 0.3], [0.1, 1.1, 0.9], [-0.2, 0.6, -0.4]])
    return mesh("fan", v, [[0, 1, 2], [1, 0, 3], [0, 1, 4]], RED)


def _many(seed=7):
    rng = np.random.default_rng(seed)
    balls = [sphere(f"ball{i}", [*rng.uniform(-2.5, 2.5, 1), rng.uniform(0.4, 2.0),
                                 rng.uniform(-2.5, 2.0)], rng.uniform(0.15, 0.35), RED,
                    subdivisions=1)
             for i in range(40)]
    return [_floor()] + balls


BUILT = {
    # the eye under a slab lit from above: inside the slab's shadow volume
    "eye inside a volume": _scene(
        [_floor(20), box("slab", [0, 2.5, 0], [4, 0.2, 4], RED)], [PointLight([0, 5, 0])],
        eye=(0.6, 1.1, 1.6), target=(-0.4, 0.4, -3.0), fov=60),
    # eye outside every volume, but a big near plane reaches into the box's volume
    "near plane cuts a volume": _scene(
        [_floor(), box("box", [0, 1.5, 0], [1, 1, 1], RED)], [PointLight([0, 4, 0])],
        eye=(0.9, 0.8, 1.2), target=(-1.0, 0.0, -2.0), near=0.5, fov=70),
    "overlapping volumes": _scene(
        [_floor(), box("low", [0, 0.6, 0], [1, 1.2, 1], RED),
         box("mid", [0.5, 1.6, 0.4], [1.2, 0.2, 1.2], RED),
         sphere("high", [-0.3, 2.6, 0.2], 0.5, RED, subdivisions=2)],
        [PointLight([1.0, 5.0, 1.0]), PointLight([-2.0, 4.0, 2.0], intensity=0.5)]),
    "many occluders": _scene(_many(), [PointLight([1.0, 6.0, 2.0])]),
    "grazing light": _scene(
        [_floor(), box("a", [0, 0.5, 0], [1, 1, 1], RED, Transform(rotation=[0, 30, 0])),
         sphere("b", [1.5, 0.6, -1.0], 0.6, RED, subdivisions=2)],
        [DirectionalLight([1.0, -0.07, 0.3])]),
    "point, directional and spot": _scene(
        [_floor(), box("a", [0, 0.5, 0], [1, 1, 1], RED),
         sphere("b", [1.4, 0.7, 0.8], 0.7, RED, subdivisions=2)],
        [PointLight([-2.0, 4.0, 1.0], intensity=0.5), DirectionalLight([0.3, -1.0, -0.4]),
         SpotLight([2.0, 3.5, 2.0], [-0.5, -1.0, -0.6], cone_angle=25.0)]),
    "open single quad": _scene(
        [_floor(), plane("quad", point=[0, 1.2, 0], normal=[0.2, 1, 0.1], size=[1.5, 1.0],
                         material=RED)],
        [PointLight([0.5, 4.0, 1.0])]),
    "non-manifold fan": _scene([_floor(), _fan()], [PointLight([0.3, 4.0, 1.5])]),
    "duplicated seam vertices": _scene(
        [_floor(), _soup(sphere("s", [0, 1.0, 0], 0.8, RED, subdivisions=2), "ball soup"),
         _soup(box("b", [1.6, 0.4, -0.5], [0.8, 0.8, 0.8], RED), "box soup")],
        [PointLight([1.0, 4.0, 2.0])]),
    "inconsistent winding": _scene(
        [_floor(), _flip_some(sphere("s", [0, 1.0, 0], 0.8, RED, subdivisions=2), "ball"),
         _flip_some(box("b", [1.6, 0.4, -0.5], [0.8, 0.8, 0.8], RED), "box")],
        [PointLight([1.0, 4.0, 2.0]), DirectionalLight([-0.3, -1.0, -0.2], intensity=0.5)]),
}


@pytest.mark.parametrize("name", sorted(BUILT))
def test_built_scenes(ctx, reference, assert_masks_match, name):
    scene = BUILT[name]
    ref_lit, ref_cov = reference(name, scene)
    with Renderer(scene, ctx) as r:
        results = {run: r.render(*run) for run in RUNS}
    for (method, silhouettes), res in results.items():
        assert_masks_match(res, ref_lit, ref_cov, f"{method}-{silhouettes}")
    np.testing.assert_array_equal(results["auto", "cpu"].lit, results["auto", "gpu"].lit)
    np.testing.assert_array_equal(results["zfail", "cpu"].lit, results["zfail", "gpu"].lit)


def test_zpass_is_visibly_wrong_with_the_eye_inside_a_volume(ctx, reference):
    """The failure z-fail exists for: z-pass counts from the eye, which is already inside the
    slab's volume, so its counts are off by one over most of the image; auto picks z-fail."""
    scene = BUILT["eye inside a volume"]
    ref_lit, ref_cov = reference("eye inside a volume", scene)
    with Renderer(scene, ctx) as r:
        zpass = r.render("zpass")
        auto = r.render("auto")
    wrong = (zpass.lit != ref_lit).mean()
    assert wrong > 0.2, f"z-pass should be visibly wrong here, only {wrong:.1%} differ"
    assert auto.zfail[0].tolist() == [False, True]  # the floor's volume stays below the floor


def test_auto_picks_zfail_where_the_near_plane_cuts(ctx):
    with Renderer(BUILT["near plane cuts a volume"], ctx) as r:
        assert r.render("auto").zfail[0].tolist() == [False, True]


@pytest.mark.parametrize("name", ["overlapping volumes", "many occluders", "grazing light"])
def test_zpass_matches_where_nothing_cuts_the_near_plane(ctx, reference, assert_masks_match,
                                                         name):
    scene = BUILT[name]
    ref_lit, ref_cov = reference(name, scene)
    with Renderer(scene, ctx) as r:
        res = r.render("zpass")
        assert not r.render("auto").zfail[:, 1:].any()
    assert_masks_match(res, ref_lit, ref_cov, "zpass")


# ---- seeded random scenes ---------------------------------------------------------------------

def _random_scene(seed: int) -> Scene:
    """A floor, a few boxes, spheres and open triangle soups (some flipped, some unwelded) at
    random, 1-3 random lights of every kind, and a camera anywhere above the floor, often
    under or among the casters (inside their volumes, near plane cutting them)."""
    rng = np.random.default_rng(seed)
    objects = [_floor(16)]
    for i in range(rng.integers(2, 6)):
        kind = rng.integers(0, 3)
        centre = [rng.uniform(-2, 2), rng.uniform(0.3, 2.5), rng.uniform(-2, 2)]
        if kind == 0:
            obj = box(f"box{i}", centre, rng.uniform(0.2, 1.2, 3), RED,
                      Transform(rotation=rng.uniform(0, 90, 3)))
        elif kind == 1:
            obj = sphere(f"ball{i}", centre, rng.uniform(0.2, 0.7), RED, subdivisions=1)
        else:
            pts = np.array(centre) + rng.normal(scale=0.5, size=(6, 3))
            obj = mesh(f"soup{i}", pts, rng.choice(6, size=(5, 3), replace=True), RED)
            faces = obj.faces[(obj.faces[:, 0] != obj.faces[:, 1]) &
                              (obj.faces[:, 1] != obj.faces[:, 2]) &
                              (obj.faces[:, 0] != obj.faces[:, 2])]
            if len(faces) == 0:
                continue
            obj = mesh(f"soup{i}", pts, faces, RED)
        if rng.random() < 0.3:
            obj = _soup(obj, obj.name)
        if rng.random() < 0.3:
            obj = _flip_some(obj, obj.name, seed)
        objects.append(obj)
    lights = []
    for _ in range(rng.integers(1, 4)):
        kind = rng.integers(0, 3)
        pos = [rng.uniform(-3, 3), rng.uniform(3, 6), rng.uniform(-3, 3)]
        if kind == 0:
            lights.append(PointLight(pos))
        elif kind == 1:
            lights.append(DirectionalLight([rng.uniform(-1, 1), -1, rng.uniform(-1, 1)]))
        else:
            lights.append(SpotLight(pos, [rng.uniform(-0.5, 0.5), -1, rng.uniform(-0.5, 0.5)],
                                    cone_angle=rng.uniform(15, 60)))
    eye = [rng.uniform(-3, 3), rng.uniform(0.4, 3.0), rng.uniform(-3, 4)]
    target = [rng.uniform(-1, 1), rng.uniform(0, 1), rng.uniform(-1, 1)]
    return _scene(objects, lights, eye=eye, target=target, near=rng.choice([0.05, 0.3]))


@pytest.mark.parametrize("seed", range(8))
def test_random_scenes(ctx, reference, assert_masks_match, seed):
    scene = _random_scene(seed)
    ref_lit, ref_cov = reference(f"random {seed}", scene)
    with Renderer(scene, ctx) as r:
        for run in [("auto", "cpu"), ("auto", "gpu"), ("zfail", "cpu")]:
            assert_masks_match(r.render(*run), ref_lit, ref_cov, "-".join(run))
