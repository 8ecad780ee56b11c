"""`occluders._topology`: a closed, consistently wound surface found, and every way to miss
being one refused (the quick test on the welded ids, `_closed`, must agree with the whole, and
its first sums never refuse a closed one);
`weld` numbers points as np.unique(axis=0) does."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from raytrace import occluders
from raytrace.occluders import _closed, _topology


def _ball():
    ico = trimesh.creation.icosphere(subdivisions=2)
    return ico.vertices[ico.faces], np.asarray(ico.faces) * 7 + 3   # welded ids, not compact


def test_a_closed_ball_has_a_topology():
    corners, welded = _ball()
    points, edges, sides = _topology(corners, welded)
    assert _closed(welded)
    assert len(points) == len(np.unique(welded)) and len(edges) == 3 * len(welded) // 2
    assert (sides[:, 0] != sides[:, 1]).all()


@pytest.mark.parametrize("broken", ["a face missing", "a face flipped", "a face twice",
                                    "an edge of one corner"])
def test_every_other_surface_has_none(broken):
    corners, welded = _ball()
    if broken == "a face missing":
        corners, welded = corners[1:], welded[1:]
    elif broken == "a face flipped":
        welded = welded.copy()
        welded[0] = welded[0, ::-1]
    elif broken == "a face twice":
        corners, welded = np.concatenate([corners, corners[:1]]), np.r_[welded, welded[:1]]
    else:
        welded = welded.copy()
        welded[0, 1] = welded[0, 0]
    assert not _closed(welded)
    assert _topology(corners, welded) is None


def test_the_quick_sums_refuse_no_closed_surface():
    """`_closed`'s first test (the sums of f(a) g(b) and f(b) g(a) over the directed edges)
    holds on every closed, consistently wound surface: closed meshes of several shapes, their
    corner ids relabelled at random (up to 2^40), the faces shuffled and each one's corners
    turned, so the sorts after it decide."""
    rng = np.random.default_rng(7)
    meshes = [trimesh.creation.icosphere(subdivisions=s) for s in range(4)] + [
        trimesh.creation.box(), trimesh.creation.cylinder(1.0, 2.0, sections=17),
        trimesh.creation.capsule(), trimesh.creation.torus(1.0, 0.3)]
    for mesh in meshes:
        assert mesh.is_watertight and mesh.is_winding_consistent
        faces = np.asarray(mesh.faces)
        for _ in range(5):
            label = rng.choice(1 << 40, size=len(mesh.vertices), replace=False)
            turned = rng.integers(0, 3, len(faces))[:, None]
            welded = label[np.take_along_axis(faces, (np.arange(3) + turned) % 3, axis=1)]
            assert _closed(welded[rng.permutation(len(faces))])


def test_an_open_surface_is_refused_before_the_sorts(monkeypatch):
    """A scanned mesh is mostly open: `_closed` refuses one by its sums, no sort run."""
    corners, welded = _ball()

    def no_sort(*args, **kwargs):
        raise AssertionError("sorted")

    monkeypatch.setattr(occluders.np, "sort", no_sort)
    for open_one in (welded[1:], welded[:-5], np.r_[welded, welded[:1]]):
        assert not _closed(open_one)


@pytest.mark.parametrize("far", [0.0, 1e4])
def test_a_runs_box_and_sphere_hold_its_clusters(far):
    """`Objects.run_*`: each run of RUN consecutive clusters has a box that holds theirs and
    a sphere that holds their spheres (what lets `blockkernels.block_meets` pass over it),
    on a soup of small and large triangles, also 1e4 away."""
    rng = np.random.default_rng(11)
    corners = rng.normal(far, 1.0, (3000, 1, 3)) + rng.normal(0, 0.02, (3000, 3, 3)) * \
        10.0 ** rng.integers(-3, 2, (3000, 1, 1))
    ids = rng.integers(0, 3, 3000)
    o = occluders.objects(corners, ids)
    C, R = len(o.members), len(o.run_lo)
    assert R == -(-C // occluders.RUN) and R > 10
    run = np.arange(C) // occluders.RUN
    assert (o.run_lo[run] <= o.lo).all() and (o.run_hi[run] >= o.hi).all()
    reach = np.linalg.norm(o.centre - o.run_centre[run], axis=1) + o.radius
    assert (reach <= o.run_radius[run]).all()
    # and not loose: the farthest cluster's sphere touches its run's, but for the margin
    assert np.allclose(np.maximum.reduceat(reach, np.arange(0, C, occluders.RUN)),
                       o.run_radius, rtol=1e-8)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_weld_numbers_the_points_as_numpys_unique_rows_does(dtype):
    """`occluders.weld` against np.unique(axis=0)'s inverse: repeated points, points that
    differ in one coordinate only, -0.0 beside 0.0, a NaN-free float grid."""
    rng = np.random.default_rng(5)
    points = rng.integers(-3, 4, (4000, 3)).astype(dtype) * dtype(0.5)
    points[::7, 1] = -0.0
    points[3::11, 2] = dtype(1e-30)
    got = occluders.weld(points)
    want = np.unique(points, axis=0, return_inverse=True)[1].reshape(-1)
    assert len(np.unique(want)) < len(points) // 2          # many repeated
    assert np.array_equal(got, want)
    assert occluders.weld(np.zeros((0, 3), dtype)).shape == (0,)


@pytest.mark.parametrize("n", [0, 1, 2, 17, 5000])
def test_the_stable_order_of_codes_is_numpys(n):
    """`occluders._stable_order` (one sort of each code with its place) against
    np.argsort(kind="stable"): many ties, the largest codes, and codes past its bits (its
    fallback)."""
    rng = np.random.default_rng(n)
    for top in (8, 1 << 30, (1 << 32) - 1, 1 << 40):
        codes = rng.integers(0, top, n, dtype=np.int64)
        if n:
            codes[rng.integers(0, n, n // 2)] = top - 1
        assert np.array_equal(occluders._stable_order(codes),
                              np.argsort(codes, kind="stable")), top


def test_morton_codes_put_bit_b_of_axis_a_at_bit_3b_plus_a():
    """`occluders._morton` (bits spread by shifts and masks) against the codes written bit by
    bit, on the grid's corners and random points."""
    rng = np.random.default_rng(2)
    points = np.r_[rng.normal(size=(3000, 3)), [[-1e3, -1e3, -1e3], [1e3, 1e3, 1e3]]]
    lo, span = points.min(axis=0), np.ptp(points, axis=0)
    cell = np.floor((points - lo) / span * 1023.999).astype(np.int64)
    want = [sum(((int(c[a]) >> b) & 1) << (3 * b + a) for b in range(10) for a in range(3))
            for c in cell]
    got = occluders._morton(points)
    assert got.tolist() == want
    assert got.max() == (1 << 30) - 1 and got.min() == 0


@pytest.mark.parametrize("seed", range(4))
def test_the_kernels_give_numpys_objects_to_the_bit(seed, monkeypatch):
    """`occluderkernels` (the triangles' normals and the members' packed rows, boxes, kinds
    and corner ids, in numba) against numpy's path, every array to the bit: a closed ball and
    an object of random triangles (some level, some degenerate: two corners at one point,
    -0.0 beside 0.0 among the coordinates), scaled from 1e-6 to 1e4, in padded clusters."""
    pytest.importorskip("numba")
    rng = np.random.default_rng(seed)
    ball, welded = _ball()
    far = 10.0 ** rng.uniform(-6, 4)
    sheet = rng.normal(0, 1, (37, 3, 3)) * far
    sheet[:5, :, 1] = 0.0
    sheet[2:5, 1] = sheet[2:5, 0]                    # degenerate: two corners one point
    sheet[:3, :, 0] *= -0.0                          # signed zeros
    corners = np.concatenate([ball * far, sheet])
    ids = np.r_[np.zeros(len(ball), np.int64), np.ones(len(sheet), np.int64)]
    welded = np.r_[welded, welded.max() + 1 + np.arange(3 * len(sheet)).reshape(-1, 3)]
    got = occluders.objects(corners, ids, None, welded)
    monkeypatch.setattr(occluders, "kernels", lambda name: None)
    want = occluders.objects(corners, ids, None, welded)
    assert len(got.members) * occluders.CLUSTER > len(corners)        # padded clusters
    assert want.cones is None and got.cones is not None      # the block path's, numba only
    for field in _array_fields(want):
        a, b = getattr(got, field), getattr(want, field)
        assert a.dtype == b.dtype and a.tobytes() == b.tobytes(), field


def _array_fields(objects) -> list:
    """The array fields of `occluders.Objects` (bodies is a list)."""
    return [f for f in objects._fields if isinstance(getattr(objects, f), np.ndarray)]
