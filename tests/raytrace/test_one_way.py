"""The block path's one-way rule (`raytrace.onewaykernels`): an object's triangles turned away
from every point of a block left out where the object and its holes' caps wind 0 times about
the block's points and the light.  Held to the pixel-by-pixel path (`exact_soft.BLOCK` 0,
itself held to the triangle-by-triangle union by test_exact_fast.py) on open shells whose
holes face the pixels, one seen from outside (a segment to the light through the hole meets
only triangles turned away: the hole's cone must keep them) and one seen from within (the
eye's ray reaches its pixels through the hole: the rule must be off there); the holes
against a union-find of the edges used once; the rule's switches against hand-made cases."""

from __future__ import annotations

import numpy as np
import pytest

import raytrace.blockwindings
import raytrace.exact_soft
from raytrace import polygons

pytest.importorskip("numba")
pytest.importorskip("shapely")
trimesh = pytest.importorskip("trimesh")

# test_block_windings.py's bound: the block path's outline differs from the pixel's own
# outside the light, so the measures agree to rounding, not to the bit
ROUNDING = 1e-12


def _shell(kind: str, centre, radius: float, seed: int = 5) -> tuple[np.ndarray, np.ndarray]:
    """A noisy icosphere (5,120 faces whole), outward-wound: (vertices, faces) of all of it
    but a small cap at its bottom (`holed`: a hole ~0.4 of its radius across, facing down)
    or at its top (`jar`: ~0.5 across, facing up)."""
    ico = trimesh.creation.icosphere(subdivisions=4, radius=radius)
    rng = np.random.default_rng(seed)
    v = ico.vertices * (1 + 0.03 * rng.standard_normal((len(ico.vertices), 1)))
    f = np.asarray(ico.faces)
    y = v[f].mean(axis=1)[:, 1] / radius
    return v + centre, f[y < 0.85 if kind == "jar" else y > -0.93]


def _scene(kind: str, size: int):
    """'holed': a ball held above a floor, a small hole in it facing the floor, the eye low,
    outside it and its hole's ball;
    'jar': a holed ball seen from above, the eye looking in through its hole, the light to
    one side (the wall shades the inside); one rect light each."""
    from shadowvol.primitives import mesh, plane
    from shadowvol.scene import AreaLight, Camera, Material, Scene
    matte = Material(diffuse=[0.8, 0.8, 0.8])
    if kind == "holed":
        shell = _shell("holed", [0.0, 1.5, 0.0], 0.6)
        light = AreaLight("rect", [0.4, 4.0, 0.3], normal=[0.1, -1, 0.05], size=[1.6, 1.4],
                          samples=4)
        camera = Camera(eye=[0.0, 0.5, 4.0], target=[0.0, 0.0, 0.0], fov_y=50.0)
    else:
        shell = _shell("jar", [0.0, 0.9, 0.0], 0.7)
        light = AreaLight("rect", [2.2, 3.0, 0.2], normal=[-0.6, -1, 0.0], size=[1.0, 1.0],
                          samples=4)
        camera = Camera(eye=[0.0, 4.2, 0.9], target=[0.0, 0.6, 0.0], fov_y=30.0)
    return Scene(camera=camera,
                 objects=[plane("floor", point=(0, 0, 0), size=[8, 8], material=matte),
                          mesh("shell", shell[0], shell[1], material=matte)],
                 lights=[light], width=size, height=size, ambient=[0, 0, 0])


def _ruled(monkeypatch) -> dict:
    """Counts, over the frame's calls: the blocks, the unsteady triangles the rule may leave
    out, and the calls where the shell (object 1) may take the rule (`_one_way`)."""
    blocks = polygons.kernels("blockkernels")
    seen = {"blocks": 0, "may": 0, "shell": 0}
    plain, one_way = blocks.block_edges, raytrace.blockwindings._one_way

    def counted(*args):
        got = plain(*args)
        seen["blocks"] += len(args[0]) - 1
        seen["may"] += int(got[9].sum())
        return got

    def ways(*args):
        got = one_way(*args)
        seen["shell"] += int(got[1])
        return got

    monkeypatch.setattr(blocks, "block_edges", counted)
    monkeypatch.setattr(raytrace.blockwindings, "_one_way", ways)
    return seen


@pytest.mark.parametrize("kind", ["holed", "jar"])
def test_the_one_way_rule_gives_the_pixel_by_pixel_measures(kind, monkeypatch):
    from raytrace.exact_soft import exact_visibility
    scene = _scene(kind, 48)
    monkeypatch.setattr(raytrace.exact_soft, "BLOCK", 0)
    want = exact_visibility(scene)
    v = want.visibility[0]
    assert ((v > 0) & (v < 1)).sum() > 40
    monkeypatch.setattr(raytrace.exact_soft, "BLOCK", 2)
    seen = _ruled(monkeypatch)
    got = exact_visibility(scene)
    assert np.abs(got.visibility - want.visibility).max() <= ROUNDING
    assert np.abs(got.irradiance - want.irradiance).max() <= ROUNDING
    assert seen["blocks"] > 50 and seen["shell"] > 0 and seen["may"] > 0


def _loops(vertices: np.ndarray, faces: np.ndarray) -> list[np.ndarray]:
    """The corners of each boundary loop of a mesh, from its edges used once (a plain
    union-find over them, apart from `occluderkernels.holes`' pass)."""
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]),
                    axis=1)
    pairs, count = np.unique(edges, axis=0, return_counts=True)
    rim = pairs[count == 1]
    parent = {int(a): int(a) for a in rim.ravel()}

    def root(a):
        while parent[a] != a:
            a = parent[a]
        return a
    for a, b in rim:
        parent[root(int(a))] = root(int(b))
    groups: dict[int, list[int]] = {}
    for a in parent:
        groups.setdefault(root(a), []).append(a)
    return [vertices[sorted(g)] for g in groups.values()]


def test_the_holes_are_the_boundarys_loops():
    """`occluderkernels.holes` on three objects: an icosphere with a cap cut away at each
    pole (two holes), a whole one (none) and a lone triangle (one): each loop's ball holds
    its corners about their mean (each corner is on two of its edges, so the edges' mean
    is the corners'), and each object's box (`occluders.Objects.holes`' last two, from its
    clusters) is its corners'."""
    from raytrace.occluders import objects, weld
    ico = trimesh.creation.icosphere(subdivisions=2)
    v, f = np.asarray(ico.vertices), np.asarray(ico.faces)
    y = v[f].mean(axis=1)[:, 1]
    cut = f[np.abs(y) < 0.8]
    parts = [(v, cut), (v + [3.0, 0, 0], f), (np.array([[0, 0, 5.0], [1, 0, 5], [0, 1, 5]]),
                                               np.array([[0, 1, 2]]))]
    corners = np.concatenate([pv[pf] for pv, pf in parts])
    owner = np.concatenate([np.full(len(pf), j) for j, (_, pf) in enumerate(parts)])
    welded = weld(corners.reshape(-1, 3)).reshape(-1, 3)
    at, centre, radius = polygons.kernels("occluderkernels").holes(
        welded, corners, owner.astype(np.int64), 3)
    assert list(np.diff(at)) == [2, 0, 1]
    lo, hi = objects(corners, owner, None, welded).holes[3:]
    for j, (pv, pf) in enumerate(parts):
        assert np.array_equal(lo[j], pv[pf].reshape(-1, 3).min(axis=0))
        assert np.array_equal(hi[j], pv[pf].reshape(-1, 3).max(axis=0))
        loops = _loops(pv, pf)
        assert len(loops) == at[j + 1] - at[j]
        for corners_of in loops:
            mean = corners_of.mean(axis=0)
            g = at[j] + np.argmin(np.linalg.norm(centre[at[j]:at[j + 1]] - mean, axis=1))
            assert np.allclose(centre[g], mean, atol=1e-12)
            far = np.linalg.norm(corners_of - centre[g], axis=1).max()
            assert far <= radius[g] <= far * (1 + 1e-5) + 1e-12


def test_an_object_takes_the_rule_only_apart_from_the_eye_and_the_light():
    """`blockwindings._one_way`: an object may take the rule where its box lies farther from
    the eye (the origin) than the rays' starts, apart from the light's corners' box, and it
    has no more than HOLES holes; not where the eye or the light reaches its box."""
    from raytrace.occluders import objects, weld
    ico = trimesh.creation.icosphere(subdivisions=1)
    v, f = np.asarray(ico.vertices), np.asarray(ico.faces)
    corners = (v + [0, 0, -5.0])[f]
    welded = weld(corners.reshape(-1, 3)).reshape(-1, 3)
    objs = objects(corners, np.zeros(len(f), np.int64), None, welded)
    light = np.array([[-0.5, 3.0, -5.5], [0.5, 3.0, -5.5], [0.5, 3.0, -4.5]])
    one_way = raytrace.blockwindings._one_way
    assert one_way(objs, light, 0.1).tolist() == [True]
    assert one_way(objs, light, np.inf).tolist() == [False]          # no eye given
    assert one_way(objs, light, 4.5).tolist() == [False]             # the rays start at it
    assert one_way(objs, light - [0, 2.5, 0], 0.1).tolist() == [False]   # the light in it
    near = corners + [0, 0, 5.0]                                     # the eye in its box
    objs_near = objects(near, np.zeros(len(f), np.int64), None, welded)
    assert one_way(objs_near, light + [0, 0, 5.0], 0.1).tolist() == [False]


def test_a_triangle_through_a_pixels_point_takes_its_object_off_the_rule():
    """`onewaykernels.through`: a triangle that passes through a pixel's p (not its own, nor
    coplanar with it) puts the object's winding about p in doubt; one off p's plane, or p's
    own, does not."""
    from raytrace.occluders import objects, weld
    from raytrace.blockkernels import FACING
    from raytrace.candidates import COPLANAR_RELATIVE
    p = np.array([[0.25, 0.25, -3.0]])
    tris = np.array([[[0, 0, -3.0], [1, 0, -3.0], [0, 1, -3.0]],          # p's own
                     [[0.25, 0.25, -3.5], [0.25, 0.25, -2.5], [1, 1, -3.0]],   # through p
                     [[0.25, 0.25, -3.5], [0.25, 0.26, -2.5], [1, 1, -3.0]]])  # beside it
    welded = weld(tris.reshape(-1, 3)).reshape(-1, 3)
    objs = objects(tris, np.arange(3), None, welded)
    oneway = polygons.kernels("onewaykernels")
    own = np.array([0])
    got = []
    for t in range(3):
        c, k = np.argwhere(objs.members == t)[0]
        got.append(oneway.through(t, c, k, 0, 1, objs.packed, p, own, tris, objs.normal,
                                  objs.offset, objs.scale, COPLANAR_RELATIVE, FACING))
    assert got == [False, True, False]


def test_no_block_takes_the_rule_where_the_frame_is_not_the_eyes(monkeypatch):
    """The rule measures the eye's segments from the frame's origin: with a backend framed
    at another eye (`scene_backend` of the scene seen from elsewhere), no object takes it,
    and the measures are the pixel-by-pixel path's all the same."""
    import dataclasses
    from raytrace.exact_soft import exact_visibility
    from raytrace.masks import scene_backend
    scene = _scene("holed", 24)
    elsewhere = scene.replace(camera=dataclasses.replace(scene.camera, eye=[0.3, 0.6, 4.2]))
    backend = scene_backend(elsewhere, "embree")
    monkeypatch.setattr(raytrace.exact_soft, "BLOCK", 0)
    want = exact_visibility(scene, backend)
    monkeypatch.setattr(raytrace.exact_soft, "BLOCK", 2)
    seen = _ruled(monkeypatch)
    got = exact_visibility(scene, backend)
    assert seen["blocks"] > 0 and seen["shell"] == 0
    assert np.abs(got.visibility - want.visibility).max() <= ROUNDING


@pytest.mark.parametrize("seed", range(10))
def test_a_cluster_passed_whole_as_turned_away_is_so_member_by_member(seed):
    """`blockkernels._ahead` and `_behind` (a cluster left out whole, from its sphere,
    normal cone and heights' range) against `_steady` member by member: wherever they pass
    a cluster for a block of points, `_steady` gives each member -1 (turned away from each
    point, free from each, carried within reach).  Bumpy sheets of small or long triangles
    (their boxes across their cluster's sphere), their normals within a few degrees to a
    few tens of one axis, and blocks of points seen at angles about the cone's edge (90
    degrees + its half angle), near and far, under reaches about the members' own bounds
    (half the time just over the most of them): some clusters pass, some only just fail.
    One sheet in four is 1/100 as wide, its clusters' spheres small beside the points'
    distances, so the bound is tight to a few hundredths of them (a facing bound loosened
    by 0.05 fails here)."""
    from raytrace import occluders
    blocks, facing = polygons.kernels("blockkernels"), polygons.kernels("facingkernels")
    rng = np.random.default_rng(seed)
    passed = 0
    for trial in range(30):
        tilt = 10.0 ** rng.uniform(-2.5, -0.3)
        wide = 1.0 if trial % 4 else 0.01
        centres = rng.uniform(-1, 1, (256, 3)) * [1, 1, 0.01] * wide
        # small triangles, or long ones (their boxes across their cluster's sphere)
        size = (0.03 if trial % 3 else 0.5) * wide
        corners = centres[:, None] + rng.normal(0, size, (256, 3, 3)) * [1, 1, tilt]
        up = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])[:, 2] > 0
        corners[~up] = corners[~up][:, ::-1]                 # every normal toward +z
        # the points' own triangle: one far off, upright (no member's plane)
        corners = np.concatenate([corners, [[[50, 0, 0], [50, 1, 0], [50, 0, 1.0]]]])
        objects = occluders.objects(corners, np.r_[np.zeros(256, np.int64), 1])
        # the light's plane z = 2, facing -z: the points below the sheet, behind it
        h = 2.0 - corners[..., 2]
        by_member = h[np.maximum(objects.members, 0)]
        flat = by_member.reshape(len(by_member), -1)
        spans = np.stack([flat.min(axis=1), flat.max(axis=1)], axis=1)
        for c in np.flatnonzero((objects.cones[:, 3] > 0) & (objects.owner == 0)):
            axis = objects.cones[c, :3]
            angle = np.arccos(objects.cones[c, 3]) + np.pi / 2 + rng.uniform(-0.1, 0.6)
            side = np.cross(axis, rng.normal(size=3))
            way = np.cos(angle) * axis + np.sin(angle) * side / np.linalg.norm(side)
            far = 10.0 ** rng.uniform(-1, 1.5)
            p = objects.centre[c] + far * way + rng.normal(0, 0.002 * far, (4, 3))
            p[:, 2] = np.minimum(p[:, 2], 2.0 - spans[c, 1] - 1e-3 * far)
            top = 2.0 - p[:, 2]
            rel = np.linalg.norm(p - [0, 0, 2.0], axis=1)
            low_top, high_top, far_rel, _ = blocks._tops(0, 4, top, rel, p)
            # the members' own reach bounds (`_steady`'s), the most: a reach just over it
            # half the time (the cluster's bound must then be over it too to pass)
            at = objects.members[c][objects.members[c] >= 0]
            box = corners[at].max(axis=1) - corners[at].min(axis=1)
            dist = np.linalg.norm(p[:, None] - corners[at, 0][None], axis=2)
            bound = (far_rel + high_top / (low_top - h[at].max(axis=1)) * (
                dist + np.linalg.norm(box, axis=1))).max()
            reach = bound * 10.0 ** (rng.uniform(0, 0.03) if trial % 2 else
                                     rng.uniform(-0.2, 0.3))
            # as `block_edges` asks: the cone and heights, then each point's floats
            grow = blocks._ahead(objects.cones[c, 3], *spans[c], low_top, high_top)
            if not (grow >= 0 and all(blocks._behind(
                    *(p[i] - objects.centre[c]), *objects.cones[c], objects.radius[c], grow,
                    far_rel, reach) for i in range(4))):
                continue
            passed += 1
            for k, t in enumerate(objects.members[c]):
                if t >= 0:
                    assert blocks._steady(
                        c, k, 0, 4, objects.packed, facing._member(c, k, objects.packed,
                                                                   by_member),
                        p, low_top, high_top, far_rel, reach, False) == -1, (trial, c, k)
    assert passed > 20
