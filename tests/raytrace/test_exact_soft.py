"""Exact visibility of area lights (`raytrace.exact_soft`) against independent witnesses.

* No occluder: V = 1 and the irradiance is the closed form of a parallel rectangle (the corner
  form factor, superposed) or disk (the off-axis parallel disk's form factor).
* A wall through the light's centre line, from the floor up to the light's plane: V = 1/2.
* A square occluder parallel to a square light: V = 1 - the product of two 1D overlaps.
* One random triangle: V against a dense float64 midpoint grid of the light.
* The sampled counts of `raytrace.soft_masks` within the bound their stratified grid allows.
* The convex bodies' hulls equal the triangle-by-triangle union.

Floor points are each pixel-centre ray met with the floor's plane in float64, as the exact
visibility's point is; both are within a few float64 roundings of each other (~1e-15 here).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from builders import FLOOR_Y, LIGHT_SIDE, LIGHT_Y, OCCLUDER_SIDE, OCCLUDER_Y, MATTE, \
    OCCLUDER_CENTER, floor_points, square_light, square_over_floor

import raytrace.occluders
from raytrace.camera import primary_rays
from raytrace.groundtruth import ground_truth
from raytrace.exact_soft import exact_visibility, visible_regions
from raytrace.soft import soft_masks
from shadowvol.arealights import grid_shape
from shadowvol.primitives import Transform, box, mesh, plane
from shadowvol.scene import AreaLight, Camera, Scene, SceneError

# A handful of float64 operations on coordinates of order 1..10: a few 1e-15 each.
ROUNDING = 1e-12


def _floor_scene(light, objects=(), size=40) -> Scene:
    floor = plane("floor", point=[0.0, FLOOR_Y, 0.0], size=[8.0, 8.0], material=MATTE)
    camera = Camera(eye=[0.0, 4.5, 5.5], target=[0.0, 0.0, -0.5], fov_y=40.0)
    return Scene(camera=camera, objects=[floor, *objects], lights=[light], width=size,
                 height=size, ambient=[0.0, 0.0, 0.0])


def _on_floor(scene):
    """Floor points (H, W, 3) of every pixel and where the floor (the first object) is what
    the pixel sees."""
    o, d = primary_rays(scene.camera, scene.width, scene.height)
    p = o + ((FLOOR_Y - o[:, 1]) / d[:, 1])[:, None] * d
    seen = ground_truth(scene, outputs=("object_id",)).object_id == 1
    return p.reshape(scene.height, scene.width, 3), seen


def _corner(a, b, c):
    """The form factor from a point to the rectangle [0, a] x [0, b] parallel to it at height
    c above, the point under its corner (odd in a and in b, so rectangles superpose)."""
    A, B = a / c, b / c
    sa, sb = np.sqrt(1 + A * A), np.sqrt(1 + B * B)
    return (A / sa * np.arctan(B / sa) + B / sb * np.arctan(A / sb)) / (2 * np.pi)


def _rect_irradiance(p, x0, x1, z0, z1, y):
    """π x the form factor from floor points p (..., 3) to the rectangle [x0, x1] x [z0, z1]
    at height y (unit radiance)."""
    c = y - p[..., 1]
    f = (_corner(x1 - p[..., 0], z1 - p[..., 2], c) - _corner(x0 - p[..., 0], z1 - p[..., 2], c)
         - _corner(x1 - p[..., 0], z0 - p[..., 2], c) + _corner(x0 - p[..., 0], z0 - p[..., 2], c))
    return np.pi * f


def _disk_irradiance(p, center, radius):
    """π x the form factor from floor points p to a parallel disk above them (off axis by r at
    height h): 1/2 (1 - (h² + r² - R²) / sqrt((h² + r² + R²)² - 4 r² R²))."""
    h2 = (center[1] - p[..., 1]) ** 2
    r2 = (center[0] - p[..., 0]) ** 2 + (center[2] - p[..., 2]) ** 2
    R2 = radius * radius
    return np.pi / 2 * (1 - (h2 + r2 - R2) / np.sqrt((h2 + r2 + R2) ** 2 - 4 * r2 * R2))


SHAPES = {
    "rect": dict(shape="rect", center=[0.0, LIGHT_Y, 0.0], normal=[0, -1, 0], size=[1.2, 0.8]),
    "disk": dict(shape="disk", center=[0.0, LIGHT_Y, 0.0], normal=[0, -1, 0], radius=0.6),
    # a regular hexagon, counter-clockwise seen from below (it emits downward)
    "polygon": dict(shape="polygon", center=None, vertices=[
        [0.6 * math.cos(a), LIGHT_Y, 0.6 * math.sin(a)] for a in np.arange(6) * math.pi / 3]),
}


@pytest.mark.parametrize("kind", ["rect", "disk"])
def test_unoccluded_light_is_whole_with_the_closed_form_irradiance(kind):
    scene = _floor_scene(AreaLight(samples=4, **SHAPES[kind]))
    found = exact_visibility(scene)
    p, floor = _on_floor(scene)
    assert floor.sum() > 0.7 * floor.size
    assert np.abs(found.visibility[0][floor] - 1).max() <= ROUNDING
    want = (_rect_irradiance(p, -0.6, 0.6, -0.4, 0.4, LIGHT_Y) if kind == "rect"
            else _disk_irradiance(p, np.array([0.0, LIGHT_Y, 0.0]), 0.6))
    assert np.abs(found.irradiance[0][floor] / want[floor] - 1).max() <= ROUNDING


@pytest.mark.parametrize("kind", ["rect", "disk", "polygon"])
def test_a_wall_through_the_centre_leaves_half(kind):
    """A wall in the plane x = 0 from the floor up to the light's plane: from either side the
    half of the light beyond it is hidden, exactly half of a centred rect, disk or hexagon.
    """
    wall = plane("wall", point=[0.0, LIGHT_Y / 2, 0.0], normal=[1, 0, 0],
                 size=[16.0, LIGHT_Y], material=MATTE)   # 16 along z, 2.5 along y
    scene = _floor_scene(AreaLight(samples=4, **SHAPES[kind]), [wall])
    found = exact_visibility(scene)
    p, floor = _on_floor(scene)
    seen = floor & (np.abs(p[..., 0]) > 1e-3)       # the wall itself is seen edge-on at x = 0
    got = found.visibility[0][seen]
    assert len(got) > 500 and np.abs(got - 0.5).max() <= ROUNDING
    if kind == "rect":   # and the irradiance is the visible half's
        right = p[..., 0] > 0
        want = np.where(right, _rect_irradiance(p, 0.0, 0.6, -0.4, 0.4, LIGHT_Y),
                        _rect_irradiance(p, -0.6, 0.0, -0.4, 0.4, LIGHT_Y))
        assert np.abs(found.irradiance[0][seen] / want[seen] - 1).max() <= ROUNDING


def test_parallel_squares_give_the_product_of_overlaps():
    """The square occluder of builders.square_over_floor against the closed form at each floor
    point."""
    scene = square_over_floor(square_light(16), size=48)
    found = exact_visibility(scene)
    p, floor = floor_points(scene)
    half = OCCLUDER_SIDE / 2
    lo = [OCCLUDER_CENTER[a] - half for a in (0, 2)]
    hi = [OCCLUDER_CENTER[a] + half for a in (0, 2)]
    k = (LIGHT_Y - FLOOR_Y) / (OCCLUDER_Y - FLOOR_Y)
    blocked = np.ones(p.shape[:-1])
    for axis, a in enumerate((0, 2)):
        s0 = p[..., a] + k * (lo[axis] - p[..., a])
        s1 = p[..., a] + k * (hi[axis] - p[..., a])
        half_light = LIGHT_SIDE / 2
        overlap = np.clip(np.minimum(s1, half_light) - np.maximum(s0, -half_light), 0, None)
        blocked *= overlap / LIGHT_SIDE
    want = 1 - blocked
    assert ((want > 0.01) & (want < 0.99) & floor).sum() > 100   # a real penumbra
    assert np.abs(found.visibility[0] - want)[floor].max() <= ROUNDING


def _segment_hits(p, targets, tri):
    """(N,) bool: the segments p -> targets (N, 3) cross the triangle tri (3, 3), float64
    (Möller-Trumbore; both sides)."""
    d = targets - p
    e1, e2 = tri[1] - tri[0], tri[2] - tri[0]
    h = np.cross(d, e2)
    a = h @ e1
    with np.errstate(divide="ignore", invalid="ignore"):
        f = 1.0 / a
        s = p - tri[0]
        u = f * (h @ s)
        q = np.cross(s, e1)
        v = f * (d @ q)
        t = f * (q @ e2)
    return (a != 0) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0) & (t < 1)


# An L-shaped light (the 1.2 x 0.8 rect less its quarter x > 0, z > 0), counter-clockwise seen
# from below; its outline lies on the midpoint grid's cell boundaries below (n = 2000 divides
# it), so it adds no crossed cell.
L_LIGHT = dict(shape="polygon", center=None, vertices=[
    [0.6, LIGHT_Y, -0.4], [0.6, LIGHT_Y, 0.0], [0.0, LIGHT_Y, 0.0], [0.0, LIGHT_Y, 0.4],
    [-0.6, LIGHT_Y, 0.4], [-0.6, LIGHT_Y, -0.4]])


def _dense_check(scene, casters, inside, n, pieces, rng, pixels=8):
    """V at penumbra floor pixels against the fraction of the light's n x n midpoint grid
    (over its 1.2 x 0.8 box, the points `inside` (u, v) keeps) whose segments miss every
    caster triangle.  The blocked set is `pieces` convex polygons (a triangle's shadow, or a
    convex body's): each outline crosses each of the n + 1 grid lines of either direction at
    most twice, so passes through at most 4 (n + 1) + 1 cells, and only the samples of those
    cells can be counted wrong, each by one."""
    found = exact_visibility(scene)
    p, floor = _on_floor(scene)
    v = found.visibility[0]
    pick = np.argwhere(floor & (v > 0.05) & (v < 0.95))
    assert len(pick) >= pixels
    grid = (np.arange(n) + 0.5) / n
    u, w = np.meshgrid(-0.6 + 1.2 * grid, -0.4 + 0.8 * grid, indexing="ij")
    keep = inside(u.ravel(), w.ravel())
    targets = np.stack([u.ravel(), np.full(u.size, LIGHT_Y), w.ravel()], 1)[keep]
    bound = pieces * (4 * (n + 1) + 1) / keep.sum()
    for y, x in pick[rng.choice(len(pick), pixels, replace=False)]:
        hit = np.zeros(len(targets), bool)
        for tri in casters:
            hit |= _segment_hits(p[y, x], targets, tri)
        assert abs(v[y, x] - (1 - hit.mean())) <= bound, (y, x, v[y, x], 1 - hit.mean())
    return pick


@pytest.mark.parametrize("light", ["rect", "L"])
def test_one_random_triangle_against_a_dense_grid(light):
    rng = np.random.default_rng(7)
    corners = np.array([[0, 1.2, 0]]) + rng.uniform(-0.7, 0.7, (3, 3)) * [1, 0.4, 1]
    shape = SHAPES["rect"] if light == "rect" else L_LIGHT
    scene = _floor_scene(AreaLight(samples=4, **shape),
                         [mesh("tri", corners, [[0, 1, 2]], MATTE)], size=32)
    inside = (lambda u, w: np.ones(u.shape, bool)) if light == "rect" else \
        (lambda u, w: (u < 0) | (w < 0))
    _dense_check(scene, [corners], inside, 2000, 1, rng)


@pytest.mark.parametrize("kind", ["rect", "disk"])
def test_contact_shadow_against_a_dense_grid(kind):
    """A box standing on the floor: the floor's penumbra right at its foot (within 3 pixels of
    pixels that see the box) against the light's midpoint grid; no margin drops the box there.
    The box is convex: its shadow is one convex polygon, whose outline crosses at most
    c = 4 (n + 1) + 1 cells.  A rect's outline runs along the grid; a disk's crosses c more,
    and the fraction's denominator (the points inside the disk) is off by at most c too: the
    bound is c / (points inside) for the rect, 3 c / (points inside) for the disk."""
    rng = np.random.default_rng(3)
    cube = box("box", center=[0.3, 0.25, -0.2], size=[0.5, 0.5, 0.5], material=MATTE,
               transform=Transform(rotation=[0, 30, 0]))
    scene = _floor_scene(AreaLight(samples=4, **SHAPES[kind]), [cube], size=48)
    seen_box = ground_truth(scene, outputs=("object_id",)).object_id == 2
    near = np.zeros_like(seen_box)
    for dy in range(-3, 4):
        for dx in range(-3, 4):
            near |= np.roll(np.roll(seen_box, dy, 0), dx, 1)
    found = exact_visibility(scene)
    p, floor = _on_floor(scene)
    v = found.visibility[0]
    pick = np.argwhere(floor & near & (v > 0.02) & (v < 0.98))
    assert len(pick) >= 6
    n = 1000
    grid = (np.arange(n) + 0.5) / n
    half_w, half_h = (0.6, 0.4) if kind == "rect" else (0.6, 0.6)
    u, w = np.meshgrid(-half_w + 2 * half_w * grid, -half_h + 2 * half_h * grid, indexing="ij")
    targets = np.stack([u.ravel(), np.full(u.size, LIGHT_Y), w.ravel()], 1)
    if kind == "disk":
        targets = targets[np.hypot(targets[:, 0], targets[:, 2]) <= 0.6]
    cells = 4 * (n + 1) + 1
    bound = (1 if kind == "rect" else 3) * cells / len(targets)
    tris = cube.vertices[cube.faces]
    for y, x in pick[rng.choice(len(pick), 6, replace=False)]:
        hit = np.zeros(len(targets), bool)
        for tri in tris:
            hit |= _segment_hits(p[y, x], targets, tri)
        assert abs(v[y, x] - (1 - hit.mean())) <= bound, (y, x, v[y, x], 1 - hit.mean())


def _random_scene(seed: int, samples: int, size: int = 36) -> Scene:
    """A rect light over a floor with floating casters: a box turned about y and x (closed,
    convex), a lone triangle (open) and three triangles on one edge (non-manifold)."""
    rng = np.random.default_rng(seed)
    light = AreaLight("rect", [rng.uniform(-0.5, 0.5), LIGHT_Y, rng.uniform(-0.5, 0.5)],
                      normal=[rng.uniform(-0.3, 0.3), -1, rng.uniform(-0.3, 0.3)],
                      size=rng.uniform(0.6, 1.4, 2), samples=samples, seed=seed)
    cube = box("box", center=[0, 0, 0], size=rng.uniform(0.2, 0.6, 3), material=MATTE,
               transform=Transform(rotation=rng.uniform(0, 60, 3),
                                   translation=[rng.uniform(-1, 1), rng.uniform(0.5, 1.5),
                                                rng.uniform(-1, 1)]))
    lone = [0, 1.0, 0] + rng.uniform(-0.8, 0.8, (3, 3)) * [1, 0.3, 1]
    spine = np.array([[0, 1.4, -0.3], [0, 1.4, 0.3]]) + [rng.uniform(-1, 1), 0, 0]
    fins = np.vstack([spine, spine.mean(0) + rng.uniform(-0.5, 0.5, (3, 3)) * [1, 0.3, 1]])
    casters = [cube, mesh("lone", lone, [[0, 1, 2]], MATTE),
               mesh("fins", fins, [[0, 1, 2], [0, 1, 3], [1, 0, 4]], MATTE)]
    return _floor_scene(light, casters, size)


def _grid_bound(region, light, nu: int, nv: int) -> float:
    """The most the count of an nu x nv stratified grid (one sample per cell) can differ from
    N x V: the cells the region's outline crosses, outside the light's own outline (a cell the
    outline misses is wholly visible or wholly hidden, its sample counted right).  A straight
    piece from a to b visits at most 1 + (|du| / cell_u + 1) + (|dv| / cell_v + 1) cells."""
    import shapely
    w, h = light.hull.max(axis=0)              # half sizes of the rect
    cu, cv = 2 * w / nu, 2 * h / nv
    total = 0.0
    for ring in shapely.get_rings(shapely.get_parts(region)):
        xy = shapely.get_coordinates(ring)
        a, b = xy[:-1], xy[1:]
        edge = ((np.isclose(np.abs(a[:, 0]), w, rtol=0, atol=1e-12)
                 & np.isclose(a[:, 0], b[:, 0], rtol=0, atol=1e-12))
                | (np.isclose(np.abs(a[:, 1]), h, rtol=0, atol=1e-12)
                   & np.isclose(a[:, 1], b[:, 1], rtol=0, atol=1e-12)))
        d = np.abs(b - a)[~edge]
        total += (3 + d[:, 0] / cu + d[:, 1] / cv).sum()
    return total


@pytest.mark.parametrize("seed", range(3))
def test_sampled_counts_within_the_stratified_bound(seed):
    scene = _random_scene(seed, samples=64)
    light = scene.lights[0]
    nu, nv = grid_shape(64)
    if light.size[1] > light.size[0]:
        nu, nv = nv, nu
    counts = soft_masks(scene).lit_count[0].astype(np.float64)
    found = exact_visibility(scene)
    regions, frame_light = visible_regions(scene, 0)
    checked = 0
    for y, x in np.argwhere(regions != None):  # noqa: E711 (an object array)
        bound = _grid_bound(regions[y, x], frame_light, nu, nv)
        error = abs(counts[y, x] - 64 * found.visibility[0, y, x])
        assert error <= bound + 64 * ROUNDING, (y, x, error, bound)
        checked += bound > 0
    assert checked > 50   # shadow edges were crossed


def test_mean_error_of_sampled_counts_falls_with_n(capsys):
    """16 -> 64 -> 256 -> 1024 stratified samples: the mean error over the penumbra falls at
    each step (a stratified grid's error goes as N^-3/4 along an edge: ~2.8x per step)."""
    means = []
    for n in (16, 64, 256, 1024):
        scene = _random_scene(5, samples=n, size=32)
        v = exact_visibility(scene).visibility[0]
        c = soft_masks(scene).lit_count[0] / n
        penumbra = (v > 0) & (v < 1)
        means.append(np.abs(c - v)[penumbra].mean())
    slope = np.polyfit(np.log([16, 64, 256, 1024]), np.log(means), 1)[0]
    print(f"mean |count/N - V| {means}, slope {slope:.2f} per log N")
    assert all(b < a for a, b in zip(means, means[1:])), means


def test_convex_hulls_equal_the_triangle_union(monkeypatch):
    """The shortcut for closed convex bodies (one hull per body) against the union of their
    triangles one by one (every object treated as not convex)."""
    scene = _random_scene(11, samples=4, size=32)
    fast = exact_visibility(scene)
    monkeypatch.setattr(raytrace.occluders, "CONVEX_TEST_FACES", 0)
    slow = exact_visibility(scene)
    assert np.abs(fast.visibility - slow.visibility).max() <= ROUNDING
    assert np.abs(fast.irradiance - slow.irradiance).max() <= ROUNDING
    assert ((fast.visibility > 0) & (fast.visibility < 1)).sum() > 30


def test_a_closed_non_convex_mesh_casts_its_back_faces_union(monkeypatch):
    """A closed, non-convex mesh (a noisy icosphere) whose shadow is the union of the faces
    turned away from each point only (it is closed and not convex: the cull applies),
    against the same triangles as two open halves (every triangle united); wound inward,
    the same (outward is taken from its signed volume)."""
    import trimesh

    ico = trimesh.creation.icosphere(subdivisions=2, radius=0.45)
    rng = np.random.default_rng(3)
    v = ico.vertices * (1 + 0.15 * rng.standard_normal((len(ico.vertices), 1)))
    v = v + [0.1, 1.1, -0.1]
    faces = np.asarray(ico.faces)
    light = AreaLight(samples=4, **SHAPES["rect"])
    whole = _floor_scene(light, [mesh("blob", v, faces, material=MATTE)], size=32)
    half = len(faces) // 2
    split = _floor_scene(light, [mesh("a", v, faces[:half], material=MATTE),
                                 mesh("b", v, faces[half:], material=MATTE)], size=32)
    found = raytrace.occluders.objects(whole.triangles()[0][whole.triangles()[1]],
                                       whole.triangles()[2])
    assert found.shell[found.object == 1].any(axis=1).all() and not found.convex.any()
    fast, slow = exact_visibility(whole), exact_visibility(split)
    ids = ground_truth(whole, outputs=("object_id",)).object_id
    seen = ids > 0                                   # the floor and the blob's own shadows
    assert ((fast.visibility > 0) & (fast.visibility < 1) & (ids == 1)).sum() > 30
    assert ((fast.visibility < 1) & (ids == 2)).sum() > 5
    assert np.abs(fast.visibility - slow.visibility)[0][seen].max() <= ROUNDING
    assert np.abs(fast.irradiance - slow.irradiance)[0][seen].max() <= ROUNDING
    flipped = _floor_scene(light, [mesh("blob", v, faces[:, ::-1], material=MATTE)], size=32)
    assert np.abs(exact_visibility(flipped).visibility - fast.visibility)[0][seen].max() \
        <= ROUNDING


def test_a_sphere_light_is_refused():
    scene = _floor_scene(AreaLight("sphere", [0, 2, 0], radius=0.3, samples=4))
    with pytest.raises(SceneError, match=r"lights\[0\]\.type.*sphere light has no exact"):
        exact_visibility(scene)


def test_far_from_the_origin_the_same():
    """The parallel squares moved 1e4 along x and z: V is the same up to the rounding of
    coordinates of 1e4 (ulp 1.8e-12; the shadow edges move by a few of them, times the
    projection's factor 2.5, over a light of 1.2: < 1e-10)."""
    import dataclasses
    scene = square_over_floor(square_light(16), size=32)
    shift = np.array([1e4, 0.0, 1e4])
    moved = scene.replace(
        objects=[dataclasses.replace(o, vertices=o.vertices + shift) for o in scene.objects],
        lights=[AreaLight("rect", scene.lights[0].center + shift, normal=[0, -1, 0],
                          size=[LIGHT_SIDE, LIGHT_SIDE], samples=16)],
        camera=dataclasses.replace(scene.camera, eye=scene.camera.eye + shift,
                                   target=scene.camera.target + shift))
    near, far = exact_visibility(scene), exact_visibility(moved)
    assert ((near.visibility > 0.01) & (near.visibility < 0.99)).sum() > 50
    assert np.abs(near.visibility - far.visibility).max() <= 1e-10
    assert np.abs(near.irradiance - far.irradiance).max() <= 1e-10
