"""The ray tracer's ground truth (raytrace.groundtruth) against hand-worked answers: which
object casts every shadow pixel of two overlapping occluders, depth and distance on analytic
planes and a sphere, normals, facing by its definition, cast = casters != 0 and lit equal to the
masks on every scene file, casters against a float64 brute force per object, the limits.

Budgets: ids and caster bits may differ from the analytic answer only within one pixel of an
edge of either (shadowvol.compare.maskdiff.edge_pixels); depth and distance within DEPTH_RTOL
where both hit the same object.
"""

from __future__ import annotations

import numpy as np
import pytest
from builders import CARDS, FLOOR, SCENES, cards_scene
from exact import _ray_triangles

import raytrace
from raytrace.camera import primary_rays
from raytrace.groundtruth import ground_truth
from shadowvol.cameras import calibration
from shadowvol.compare.maskdiff import edge_pixels
from shadowvol.primitives import box, plane, sphere
from shadowvol.scene import (
    AreaLight,
    Camera,
    DirectionalLight,
    PointLight,
    Scene,
    SceneError,
    SpotLight,
)
from shadowvol.scenefile import load_scene

# float32 depth from a float64 hit point: half a float32 spacing of rounding (2**-24), and the
# plane's float64 arithmetic far below that; 4 spacings allowed.
DEPTH_RTOL = 4 * 2.0 ** -23

# ---- the hand-worked scene ----------------------------------------------------------------------

def pixel_rays(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """eye (3,) and the pixel-centre directions (H, W, 3) from K and camera_to_world alone
    (not the ray tracer's own rays), each of eye-space depth 1."""
    cal = calibration(scene)
    H, W = scene.height, scene.width
    u, v = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    x = (u - cal.K[0, 2]) / cal.K[0, 0]
    y = (v - cal.K[1, 2]) / cal.K[1, 1]
    gl = np.stack([x, -y, -np.ones_like(x)], axis=-1)
    return cal.camera_to_world[:3, 3], gl @ cal.camera_to_world[:3, :3].T


def analytic_cards(scene: Scene):
    """Per pixel, by hand: the object id (0 background, 1 floor, 2 A, 3 B), the depth (inf
    for none) and the casters of the straight-down light, as bits."""
    eye, d = pixel_rays(scene)
    H, W = d.shape[:2]
    ids = np.zeros((H, W), np.uint16)
    depth = np.full((H, W), np.inf)
    hits = {}
    for k, (y, xs, zs) in enumerate([FLOOR, CARDS["A"], CARDS["B"]], start=1):
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (y - eye[1]) / d[..., 1]
        p = eye + t[..., None] * d
        inside = ((t > scene.camera.near) & (xs[0] <= p[..., 0]) & (p[..., 0] <= xs[1])
                  & (zs[0] <= p[..., 2]) & (p[..., 2] <= zs[1]))
        nearer = inside & (t < depth)
        ids[nearer], depth[nearer] = k, t[nearer]
        hits[k] = p
    casters = np.zeros((H, W), np.uint64)
    for bit, (name, k_over) in enumerate([("A", 2), ("B", 3)], start=1):
        y, xs, zs = CARDS[name]
        for k in (1, 2, 3):
            p = hits[k]
            under = ((ids == k) & (p[..., 1] < y) & (xs[0] <= p[..., 0]) & (p[..., 0] <= xs[1])
                     & (zs[0] <= p[..., 2]) & (p[..., 2] <= zs[1]))
            casters[under] |= np.uint64(1 << bit)
    return ids, depth, casters


def near_any_edge(*masks) -> np.ndarray:
    return np.logical_or.reduce([edge_pixels(m) for m in masks])


def test_two_occluders_every_shadow_pixels_casters(request):
    scene = cards_scene()
    truth = ground_truth(scene)
    ids, depth, casters = analytic_cards(scene)
    a, b = np.uint64(1 << 1), np.uint64(1 << 2)
    got = truth.casters[0, ..., 0]   # one word: at most 64 objects
    # the scene shows every case: A alone, B alone, both (the overlap), on the floor and on B
    for want, where in [(a, 1), (b, 1), (a | b, 1), (a, 3)]:
        assert ((casters == want) & (ids == where)).sum() > 20, (want, where)
    edges = near_any_edge(*[ids == k for k in range(4)], (casters & a) != 0,
                          (casters & b) != 0)
    assert not ((truth.object_id != ids) & ~edges).any()
    assert not ((got != casters) & ~edges).any()
    # cast shadow is exactly the pixels with a caster; nothing faces away from a light above
    np.testing.assert_array_equal(truth.cast[0], got != 0)
    assert not truth.attached.any()
    same = (truth.object_id == ids) & (ids > 0)
    np.testing.assert_allclose(truth.depth[same], depth[same], rtol=DEPTH_RTOL)
    assert np.isinf(truth.depth[truth.object_id == 0]).all()
    # the cards and the floor face up, toward the camera above them
    assert (truth.normal[ids > 0] == np.float32([0, 1, 0])).all()
    assert (truth.normal[truth.object_id == 0] == 0).all()


def test_a_point_light_beside_the_cards_gives_the_same_bits_as_brute_force():
    scene = cards_scene(64, 48, PointLight([0.8, 4.0, 0.4]))
    truth = ground_truth(scene)
    want, ids = exact_casters(scene)
    np.testing.assert_array_equal(truth.object_id, ids)
    check_bits(truth.casters[..., 0], want, ids, len(scene.objects))


# ---- depth and distance on a sphere ---------------------------------------------------------

def test_depth_distance_and_normals_on_a_sphere():
    ball = sphere("ball", [0.2, -0.1, -0.3], 1.0, subdivisions=4)
    scene = Scene(camera=Camera(eye=[0.5, 1.0, 3.5], target=[0.2, -0.1, -0.3], fov_y=45.0),
                  objects=[ball], lights=[PointLight([3, 3, 3])], width=96, height=80)
    truth = ground_truth(scene, ["depth", "distance", "normal"])
    eye, d = pixel_rays(scene)
    c = np.array(ball.analytic.center)
    # the faces' distances from the centre: the mesh lies between that sphere and the real one
    tri = ball.triangles
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    inscribed = float(np.min(np.abs(np.einsum("ij,ij->i", n / np.linalg.norm(n, axis=1,
                                                                              keepdims=True),
                                              tri[:, 0] - c))))

    def sphere_depth(r):  # the nearer root of |eye + t d − c| = r, t in units of depth
        oc = eye - c
        A = np.einsum("hwk,hwk->hw", d, d)
        B = 2 * d @ oc
        C = oc @ oc - r * r
        disc = B * B - 4 * A * C
        with np.errstate(invalid="ignore"):
            return np.where(disc >= 0, (-B - np.sqrt(disc)) / (2 * A), np.inf)

    outer, inner = sphere_depth(1.0), sphere_depth(inscribed)
    both = np.isfinite(inner)
    assert both.sum() > 1500
    got = truth.depth[both]
    assert (got >= outer[both] * (1 - DEPTH_RTOL)).all()
    assert (got <= inner[both] * (1 + DEPTH_RTOL)).all()
    assert np.isinf(truth.depth[~np.isfinite(outer)]).all()
    # distance = depth x the length of the depth-1 pixel direction
    length = np.linalg.norm(d, axis=-1)
    np.testing.assert_allclose(truth.distance[both], got * length[both], rtol=DEPTH_RTOL)
    # the face normal at p is within the facet's angle of the radial direction, and faces the eye
    p = eye + np.where(both, truth.depth, 0)[..., None].astype(np.float64) * d
    radial = (p - c) / np.linalg.norm(p - c, axis=-1, keepdims=True)
    cos = np.einsum("hwk,hwk->hw", truth.normal.astype(np.float64), radial)
    assert (cos[both] >= inscribed - 1e-6).all()
    np.testing.assert_allclose(np.linalg.norm(truth.normal[both], axis=-1), 1, rtol=1e-6)
    assert (np.einsum("hwk,hwk->hw", truth.normal.astype(np.float64), d)[both] < 0).all()


# ---- every scene file: consistency with the masks and the definitions ----------------------

@pytest.mark.parametrize("name", sorted(p.stem for p in SCENES.glob("*.toml")))
def test_every_scene_file_cast_is_casters_and_lit_is_the_masks(name):
    scene = load_scene(SCENES / f"{name}.toml").replace(width=160, height=120)
    lit, coverage = raytrace.shadow_masks(scene)
    truth = ground_truth(scene)
    np.testing.assert_array_equal(truth.lit, lit)
    np.testing.assert_array_equal(truth.coverage, coverage)
    np.testing.assert_array_equal(truth.cast, truth.casters.any(-1))
    np.testing.assert_array_equal(truth.casters.any(-1), truth.lit_count < truth.facing_count)
    if any(isinstance(light, AreaLight) for light in scene.lights):
        # every output of an area light: its counts are raytrace.soft_masks'
        soft = raytrace.soft_masks(scene)
        np.testing.assert_array_equal(truth.lit_count, soft.lit_count)
        np.testing.assert_array_equal(truth.facing, soft.facing)
        np.testing.assert_array_equal(truth.umbra, soft.umbra)
        np.testing.assert_array_equal(truth.penumbra, soft.penumbra)
        np.testing.assert_array_equal(truth.object_id > 0, coverage)
        return
    assert truth.cast.any() or not scene.lights  # cornell.toml has only emitters
    np.testing.assert_array_equal(truth.object_id > 0, coverage)
    assert (np.isfinite(truth.depth) == coverage).all()
    # facing by its definition, from the outputs alone: n · (light − p) > 0 and the cone
    eye, d = pixel_rays(scene)
    p = eye + np.where(coverage, truth.depth, 0)[..., None].astype(np.float64) * d
    n = truth.normal.astype(np.float64)
    for i, light in enumerate(scene.lights):
        if isinstance(light, DirectionalLight):
            to_light = np.broadcast_to(-light.direction, p.shape)
        else:
            to_light = light.position - p
        n_dot_l = np.einsum("hwk,hwk->hw", n, to_light)
        want = coverage & (n_dot_l > 0)
        if isinstance(light, SpotLight):
            away = -to_light
            want &= away @ light.direction >= light.cos_cutoff * np.linalg.norm(away, axis=-1)
        # float32 normals and depths: undecided only where n·l is within rounding of 0
        scale = np.linalg.norm(to_light, axis=-1)
        clear = np.abs(n_dot_l) > 1e-5 * scale
        np.testing.assert_array_equal(truth.facing[i][clear], want[clear])


def test_stack_casters_match_a_float64_brute_force_per_object():
    """The four staggered slabs of stack.toml: up to four casters per floor pixel."""
    scene = load_scene(SCENES / "stack.toml").replace(width=64, height=48)
    truth = ground_truth(scene)
    want, ids = exact_casters(scene)
    np.testing.assert_array_equal(truth.object_id, ids)
    check_bits(truth.casters[..., 0], want, ids, len(scene.objects))
    assert popcount(truth.casters[..., 0]).max() >= 3


def test_embree_and_numpy_agree():
    scene = load_scene(SCENES / "stack.toml").replace(width=48, height=36)
    a, b = ground_truth(scene, backend="embree"), ground_truth(scene, backend="numpy")
    for name in ("object_id", "facing", "casters"):
        assert (getattr(a, name) != getattr(b, name)).sum() <= 2, name
    same = a.object_id == b.object_id
    np.testing.assert_allclose(a.depth[same & a.coverage], b.depth[same & b.coverage],
                               rtol=DEPTH_RTOL)


def test_views_over_one_backend_build_the_object_tracers_once_and_match_a_fresh_build():
    """A turntable over one `scene_backend`: `casters` reuses its per-object tracers from the
    first view on, and every view's outputs equal a build of its own; a scene whose geometry
    changed gets its tracers rebuilt."""
    from raytrace import groundtruth
    from raytrace.masks import scene_backend
    scene = load_scene(SCENES / "stack.toml").replace(width=48, height=36)
    mt = scene_backend(scene)
    kept = None
    for eye in ([4.0, 5.0, 6.0], [-5.0, 4.0, 3.0], [0.5, 6.0, -5.0]):
        view = scene.replace(camera=Camera(eye=eye, target=[0.0, 0.3, 0.0], fov_y=40.0))
        got = ground_truth(view, backend=mt)
        kept = kept or groundtruth._OBJECT_TRACERS[mt.tracer]
        assert groundtruth._OBJECT_TRACERS[mt.tracer] is kept
        fresh = ground_truth(view, backend=scene_backend(scene))   # its own tracers
        for name, want in fresh.arrays().items():
            np.testing.assert_array_equal(got.arrays()[name], want, err_msg=name)
    import dataclasses
    moved = dataclasses.replace(scene.objects[1], vertices=scene.objects[1].vertices + 0.25)
    ground_truth(scene.replace(objects=[scene.objects[0], moved, *scene.objects[2:]]),
                 ["casters"], backend=mt)
    assert groundtruth._OBJECT_TRACERS[mt.tracer] is not kept


# ---- outputs, limits ---------------------------------------------------------------------------

def test_only_the_outputs_asked_for_and_the_calibration_always():
    scene = cards_scene(16, 12)
    truth = ground_truth(scene, ["depth", "casters"])
    assert truth.normal is None and truth.object_id is None
    assert set(truth.arrays()) == {"depth", "casters", "K", "world_to_camera",
                                   "camera_to_world", "light_position", "light_direction"}
    assert truth.casters.dtype == np.uint64 and truth.depth.dtype == np.float32
    with pytest.raises(SceneError, match="unknown output 'depths'"):
        ground_truth(scene, ["depths"])


def test_more_than_64_objects_have_casters_in_two_words():
    cubes = [box(f"c{i}", [i % 9 - 4.0, 0.2, i // 9 - 4.0], [0.3, 0.3, 0.3]) for i in range(70)]
    scene = Scene(camera=Camera(eye=[0, 8, 8], target=[0, 0, 0]),
                  objects=cubes + [plane("floor", point=(0, 0.05, 0))],
                  lights=[DirectionalLight([0.3, -1, 0.2])], width=32, height=24)
    truth = ground_truth(scene)
    assert truth.object_id.max() > 64
    assert truth.casters.shape == (1, 24, 32, 2) and truth.casters[..., 1].any()
    np.testing.assert_array_equal(truth.casters.any(-1), truth.lit_count < truth.facing_count)


# ---- the brute force ------------------------------------------------------------------------

def exact_casters(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """casters (L, H, W) uint64 and object_id (H, W) by brute force in float64 (as
    tests/exact.py judges `lit`): the nearest triangle of every float64 pixel ray, then for
    every light the segment to it tested against each object's triangles, the visible one
    skipped."""
    vertices, faces, owner = scene.triangles()
    tri = vertices[faces]
    o, d = primary_rays(scene.camera, scene.width, scene.height, unit=False)
    t = _ray_triangles(o, d, tri)
    t[t <= 0] = np.inf
    first = np.argmin(t, axis=1)
    t_hit = t[np.arange(len(o)), first]
    covered = np.isfinite(t_hit)
    ids = np.where(covered, owner[first] + 1, 0).astype(np.uint16)
    p = o + np.where(covered, t_hit, 0)[:, None] * d
    n = np.cross(tri[first, 1] - tri[first, 0], tri[first, 2] - tri[first, 0])
    n *= np.where(np.einsum("ij,ij->i", n, d) > 0, -1.0, 1.0)[:, None]
    casters = np.zeros((len(scene.lights), len(o)), np.uint64)
    for i, light in enumerate(scene.lights):
        if isinstance(light, DirectionalLight):
            seg, t_max = np.broadcast_to(-light.direction * scene.extent, p.shape), np.inf
        else:
            seg, t_max = light.position - p, 1.0
        ok = covered & (np.einsum("ij,ij->i", n, seg) > 0)
        if isinstance(light, SpotLight):
            ok &= -seg @ light.direction >= light.cos_cutoff * np.linalg.norm(seg, axis=1)
        k = np.flatnonzero(ok)
        ts = _ray_triangles(p[k], np.ascontiguousarray(seg[k]), tri)
        ts[np.arange(len(k)), first[k]] = np.inf
        between = (ts > 1e-12) & (ts < t_max)
        for j in range(len(scene.objects)):
            hit = between[:, owner == j].any(axis=1)
            casters[i, k[hit]] |= np.uint64(1 << j)
    shape = (scene.height, scene.width)
    return casters.reshape((-1,) + shape), ids.reshape(shape)


def check_bits(got: np.ndarray, want: np.ndarray, ids: np.ndarray, objects: int) -> None:
    """Every bit of every light equal off the edges (one pixel) of that bit's mask in either
    and of the object ids; the case must occur (some pixel with two or more casters)."""
    id_edges = near_any_edge(*[ids == k for k in range(objects + 1)])
    for i in range(len(got)):
        for j in range(objects):
            bit = np.uint64(1 << j)
            g, w = (got[i] & bit) != 0, (want[i] & bit) != 0
            bad = (g != w) & ~(id_edges | edge_pixels(g) | edge_pixels(w))
            assert not bad.any(), f"light {i}, object {j}: {np.argwhere(bad)[:5].tolist()}"
    assert popcount(want).max() >= 2


def popcount(bits: np.ndarray) -> np.ndarray:
    """How many bits are set in each uint64."""
    return np.unpackbits(bits.view(np.uint8)).reshape(bits.shape + (64,)).sum(axis=-1)


def test_the_numba_box_test_meets_the_boxes_numpy_meets():
    """`maskkernels.box_candidates` lists, per casting object, exactly the segments that
    `groundtruth._meets_box` finds meeting its box or leaving it: random segments, some with
    zero direction components (1/d infinite) running inside a box's face (0 · inf), bounded and
    unbounded."""
    pytest.importorskip("numba")
    from raytrace.groundtruth import _meets_box
    from raytrace.maskkernels import box_candidates

    rng = np.random.default_rng(7)
    n, b = 9, 4000
    lo = rng.uniform(-2, 1, (n, 3))
    hi = lo + rng.uniform(0, 1.5, (n, 3))
    hi[3] = lo[3]   # a flat box
    start = rng.uniform(-3, 3, (3, b))
    direction = rng.normal(size=(3, b))
    direction[rng.random((3, b)) < 0.2] = 0.0
    face = np.flatnonzero(rng.random(b) < 0.2)   # inside a box's face x = lo, along it
    box_of = rng.integers(0, n, len(face))
    start[:, face] = ((lo + hi) / 2)[box_of].T
    start[0, face] = lo[box_of, 0]
    direction[0, face] = 0.0
    with np.errstate(divide="ignore"):
        inverse = 1.0 / direction
    own_object = rng.integers(-1, n, b)
    casts = rng.random(n) < 0.8
    for end in (np.inf, rng.uniform(0, 2, b)):
        first, k = box_candidates(start, inverse, np.broadcast_to(end, (b,)).copy(), lo, hi,
                                  casts, own_object)
        for j in range(n):
            want = (np.flatnonzero(_meets_box(start, inverse, end, lo[j], hi[j])
                                   | (own_object == j)) if casts[j] else np.zeros(0, int))
            assert np.array_equal(k[first[j]:first[j + 1]], want), j


def test_the_numba_kernels_give_numpys_bytes(monkeypatch):
    """Every output of `ground_truth` (the per-pixel ones of `maskkernels.pixel_outputs`, the
    casters of `maskkernels.box_candidates`) is numpy's, byte for byte, on the numpy backend
    with and without the kernels."""
    pytest.importorskip("numba")
    import sys
    scene = load_scene(SCENES / "stack.toml").replace(width=96, height=72)
    fast = ground_truth(scene, backend="numpy").arrays()
    monkeypatch.setitem(sys.modules, "raytrace.maskkernels", None)   # import fails: numpy
    slow = ground_truth(scene, backend="numpy").arrays()
    assert fast.keys() == slow.keys()
    for name, want in slow.items():
        got = fast[name]
        assert got.dtype == want.dtype and got.tobytes() == want.tobytes(), name


def test_casters_in_parts_are_the_casters_at_once(monkeypatch):
    """The blocked segments taken a few at a time (`groundtruth.CANDIDATE_PAIRS`) give the
    same bits as all at once."""
    from raytrace import groundtruth
    scene = load_scene(SCENES / "stack.toml").replace(width=64, height=48)
    whole = ground_truth(scene, ["casters"]).casters
    assert whole.any()
    monkeypatch.setattr(groundtruth, "CANDIDATE_PAIRS", 7)
    np.testing.assert_array_equal(ground_truth(scene, ["casters"]).casters, whole)
