"""A block of pixels' shared outline (`raytrace.blockwindings`) and an outline cut to a box
about the light (`raytrace.clipkernels`), against independent witnesses: the pixel-by-pixel
path (`exact_soft.BLOCK` 0, itself held to the triangle-by-triangle union by
test_exact_fast.py), and shapely's union of the triangles measured inside the light."""

from __future__ import annotations

import numpy as np
import pytest

import raytrace.blockwindings
import raytrace.exact_soft
from raytrace import polygons, windings
from builders import SCENES
from shadowcases import loose, sheet

pytest.importorskip("numba")
shapely = pytest.importorskip("shapely")

# The block path's outline differs from the pixel's own outside the light (more triangles,
# cut to a box), so the measures agree to rounding, not to the bit (test_exact_fast's bound).
ROUNDING = 1e-12


def _scene(light_shape: str, size: int = 24, far: float = 0.0):
    """A wavy open sheet (3,042 triangles) and a noisy closed ball (1,280) over a floor under
    one area light: dense meshes, so blocks hold many steady triangles; all of it moved `far`
    along x, y and z."""
    trimesh = pytest.importorskip("trimesh")
    from shadowvol.primitives import mesh, plane
    from shadowvol.scene import AreaLight, Camera, Material, Scene
    rng = np.random.default_rng(3)
    n = 40
    x, z = np.meshgrid(np.linspace(-1.2, 0.2, n), np.linspace(-0.7, 0.7, n))
    y = 1.1 + 0.06 * np.sin(9 * x) * np.cos(7 * z) + 0.01 * rng.standard_normal((n, n))
    k = np.arange(n * n).reshape(n, n)[:-1, :-1].ravel()
    faces = np.r_[np.c_[k, k + 1, k + n + 1], np.c_[k, k + n + 1, k + n]]
    ico = trimesh.creation.icosphere(subdivisions=3, radius=0.35)
    ball = ico.vertices * (1 + 0.08 * rng.standard_normal((len(ico.vertices), 1)))
    matte = Material(diffuse=[0.8, 0.8, 0.8])
    light = AreaLight(light_shape, np.add([0.0, 2.6, 0.0], far), normal=[0.2, -1, 0.1],
                      **({"size": [1.0, 0.8]} if light_shape == "rect" else {"radius": 0.5}),
                      samples=4)
    return Scene(camera=Camera(eye=np.add([0, 4.5, 5.5], far),
                               target=np.add([0, 0, -0.3], far), fov_y=40.0),
                 objects=[plane("floor", point=(far, far, far), size=[8, 8], material=matte),
                          mesh("sheet", np.c_[x.ravel(), y.ravel(), z.ravel()] + far, faces,
                               material=matte),
                          mesh("ball", ball + [0.7, 0.8, 0.2] + far, np.asarray(ico.faces),
                               material=matte)],
                 lights=[light], width=size, height=size, ambient=[0, 0, 0])


@pytest.mark.parametrize("shape", ["rect", "disk"])
def test_blocks_give_the_pixel_by_pixel_measures(shape, monkeypatch):
    from raytrace.exact_soft import exact_visibility
    scene = _scene(shape)
    monkeypatch.setattr(raytrace.exact_soft, "BLOCK", 0)
    want = exact_visibility(scene)
    v = want.visibility[0]
    assert ((v > 0) & (v < 1)).sum() > 60 and (v == 0).sum() > 10
    blocks = polygons.kernels("blockkernels")
    shared, plain = [], blocks.block_edges

    def counted(*args):
        got = plain(*args)
        shared.append((len(got[0]), len(got[5])))
        return got
    monkeypatch.setattr(blocks, "block_edges", counted)
    settled, contacts = [], []
    plain_chains = raytrace.blockwindings.chains

    def chains(*args, **kwargs):
        got, loose, met = plain_chains(*args, **kwargs)
        settled.append(sum(c is not None for c in got))
        contacts.append(sum(c is not None for c in loose))
        return got, loose, met
    monkeypatch.setattr(raytrace.blockwindings, "chains", chains)
    for block in (2, 3, 5):
        monkeypatch.setattr(raytrace.exact_soft, "BLOCK", block)
        got = exact_visibility(scene)
        assert np.abs(got.visibility - want.visibility).max() <= ROUNDING
        assert np.abs(got.irradiance - want.irradiance).max() <= ROUNDING
    # the blocks shared outlines (steady edges counted once) and settled most pixels, a few
    # with shadows apart (on the sheet and the ball, where the triangles about p cross its
    # parallel plane: a contact; more than `windings.LOOSE` there, or a block that meets a
    # few triangles only, and the pixel is left to the pixel-by-pixel path)
    assert sum(edges for edges, _ in shared) > 1000
    assert sum(settled) >= 3 * 0.5 * scene.width * scene.height        # ~69 % each
    assert sum(contacts) >= 3 * 3                                        # 4 each


def test_carried_in_parts_gives_the_same_bytes(monkeypatch):
    """`blockwindings.chains` carries its blocks' outlines about CARRIED edges at a time
    (whole blocks): one block a part gives the same bytes as the default."""
    from raytrace.exact_soft import exact_visibility
    scene = _scene("rect", 16)
    want = exact_visibility(scene)
    monkeypatch.setattr(raytrace.blockwindings, "CARRIED", 1)
    got = exact_visibility(scene)
    assert got.visibility.tobytes() == want.visibility.tobytes()
    assert got.irradiance.tobytes() == want.irradiance.tobytes()


def _same_as_every_cluster(block_meets, args, got):
    """`block_meets`' verdicts got (on its runs) against the same call with one unbounded run:
    every cluster tested; args: its arguments before the runs'."""
    every = block_meets(*args, len(args[6]), np.full((1, 3), -np.inf), np.full((1, 3), np.inf),
                        np.zeros((1, 3)), np.full(1, np.inf))
    for a, b in zip(got, every):
        assert np.array_equal(a, b)


@pytest.mark.parametrize("shape, far", [("rect", 0.0), ("disk", 0.0), ("rect", 1e4)])
def test_the_runs_pass_over_no_cluster_a_block_meets(shape, far, monkeypatch):
    """`block_meets` passes over a run of clusters by its box and by its sphere
    (`occluders.Objects.run_*`): against one unbounded run (every cluster tested), the same
    clusters meet each block, on the sheet and the ball, also all of it moved 1e4 away."""
    from raytrace.exact_soft import exact_visibility
    blocks = polygons.kernels("blockkernels")
    plain, met = blocks.block_meets, []

    def both(*args):
        got = plain(*args)
        _same_as_every_cluster(plain, args[:13], got)
        met.append(got[0].sum())
        return got
    monkeypatch.setattr(blocks, "block_meets", both)
    exact_visibility(_scene(shape, 32, far))
    assert sum(met) > 1000


@pytest.mark.parametrize("seed", range(6))
def test_runs_of_tiny_clusters_far_out_pass_over_none_that_meets(seed):
    """`block_meets` on runs of clusters whose spheres are tiny beside their distance from the
    block (triangles 1e-9 to 1e-3 across, strewn about the pyramids' side planes by a hair,
    everything moved up to 1e3 out): the same clusters meet the block as when every cluster
    is tested (one unbounded run); some meet and some do not."""
    from raytrace import blockkernels, occluders, pyramid
    from raytrace.lightshapes import frame_light
    from shadowvol.scene import AreaLight
    rng = np.random.default_rng(seed)
    out = rng.uniform(-1, 1, 3) * 10.0 ** rng.integers(0, 4)
    light = frame_light(AreaLight("rect", out + [0.0, 3.0, 0.0], size=[1.2, 0.8],
                                  normal=rng.normal([0, -1, 0], 0.2), samples=4), np.zeros(3),
                        "l")
    base = light.center + light.hull @ light.axes
    p = out + rng.uniform(-1, 1, 3) * [1, 0.2, 1] + rng.normal(0, 1e-3, (4, 3))
    sides = np.stack([m / np.linalg.norm(m, axis=1, keepdims=True)
                      for m in pyramid.sides(light, p, base)])
    # sites on the side planes of the pixels' pyramids, a hair in or out, 16 triangles about
    # each (a cluster), the site's size across
    n = 400
    k, j = rng.integers(0, 4, n), rng.integers(0, len(sides), n)
    t = rng.uniform(0.05, 0.95, n)[:, None]
    site = p[k] + t * (base[rng.integers(0, len(base), n)] - p[k])
    site -= np.einsum("ij,ij->i", sides[j, k], site - p[k])[:, None] * sides[j, k]
    across = 10.0 ** rng.integers(-9, -2, (n, 1))
    site += sides[j, k] * across * rng.uniform(-3, 3, (n, 1))
    corners = (site[:, None, None] + rng.uniform(-0.5, 0.5, (n, 16, 3, 3))
               * across[:, None, None]).reshape(-1, 3, 3)
    obj = occluders.objects(corners, np.zeros(len(corners), np.int64))
    lo, hi = np.minimum(p, base.min(axis=0)), np.maximum(p, base.max(axis=0))
    args = (np.array([0, 4]), lo, hi, (p - light.center) @ light.normal, sides, p, obj.lo,
            obj.hi, obj.centre, obj.radius, (obj.centre - light.center) @ light.normal,
            (obj.members >= 0).sum(axis=1), np.zeros(len(obj.lo), bool))
    got = blockkernels.block_meets(*args, occluders.RUN, obj.run_lo, obj.run_hi,
                                   obj.run_centre, obj.run_radius)
    _same_as_every_cluster(blockkernels.block_meets, args, got)
    assert 0 < got[0].sum() < len(obj.lo)


@pytest.mark.parametrize("seed", range(4))
def test_a_run_keeps_a_cluster_that_its_sphere_barely_reaches(seed):
    """`block_meets`' run test at its edge: a run of 16 tiny clusters (1e-9 to 1e-3 across)
    whose farthest one just meets a pixel's side plane by the cluster test (`_above`, its
    2^-40 rounding margin included) or just misses it, far from the pixel along the plane
    (up to 1e3) and out from the origin: the same verdicts as when every cluster is tested
    (one plane, every other test open; a run radius 0.1 % short fails here)."""
    from raytrace import blockkernels, occluders
    rng = np.random.default_rng(seed)
    kept = left = 0
    for _ in range(200):
        m = rng.normal(size=3)
        m /= np.linalg.norm(m)
        p = rng.uniform(-1, 1, (1, 3)) * 10.0 ** rng.integers(0, 4)
        size = 10.0 ** rng.integers(-9, -2)
        away = rng.normal(size=3)
        away -= (away @ m) * m
        away *= 10.0 ** rng.integers(-3, 4) / np.linalg.norm(away)
        # sites: the farthest (a) just about at the plane, its mirror b, 14 between
        spread = size * 10.0 ** rng.integers(0, 3)
        middle = p[0] + away - m * spread
        pairs = rng.uniform(-0.5, 0.5, (7, 3)) * spread
        sites = np.r_[[middle + m * spread, middle - m * spread], middle + pairs, middle - pairs]
        corners = (sites[:, None, None] + rng.uniform(-0.5, 0.5, (16, 16, 3, 3)) * size
                   ).reshape(-1, 3, 3)
        obj = occluders.objects(corners, np.zeros(len(corners), np.int64))
        if len(obj.lo) != 16 or len(obj.run_lo) != 1:
            continue
        # the plane through p lowered (or raised) to a hair of the farthest cluster's test
        sides = m[None, None]
        top = np.array([1e300])
        at = np.argmax(obj.centre @ m)
        r = obj.centre[at] - p[0]
        edge = -(obj.radius[at] + 2.0 ** -40 * np.abs(r).sum())
        slack = (r @ m - edge) * (1 + rng.choice([-1, 1]) * 10.0 ** rng.uniform(-14, -6))
        q = p + m * slack                              # a pixel at that height
        args = (np.array([0, 1]), np.full((1, 3), -1e300), np.full((1, 3), 1e300), top, sides,
                q, obj.lo, obj.hi, obj.centre, obj.radius, np.zeros(16), np.full(16, 16),
                np.zeros(16, bool))
        got = blockkernels.block_meets(*args, occluders.RUN, obj.run_lo, obj.run_hi,
                                       obj.run_centre, obj.run_radius)
        _same_as_every_cluster(blockkernels.block_meets, args, got)
        kept += got[0].any()
        left += not got[0].any()
    assert kept > 20 and left > 20


def _traced_tiles(monkeypatch) -> list:
    """The tiles `exact_visibility` hands `for_each_tile` on each call, (start, stop) rows
    each, recorded into the list returned."""
    traced, plain = [], raytrace.exact_soft.for_each_tile

    def recorded(work, tiles, tracer):
        traced.append([(t.start, t.stop) for t in tiles])
        return plain(work, tiles, tracer)
    monkeypatch.setattr(raytrace.exact_soft, "for_each_tile", recorded)
    return traced


def test_the_tiles_give_the_same_bytes(monkeypatch):
    """`exact_visibility` cuts a frame into tiles of whole blocks (`exact_soft.BLOCK` rows a
    block): a tile a thread, and tiles of 2, 3 (rounded up to 4) and 6 rows, give the same
    bytes, and the tiles asked for are the ones traced."""
    from raytrace.exact_soft import exact_visibility
    scene = _scene("rect", 24)
    traced = _traced_tiles(monkeypatch)
    monkeypatch.setattr(raytrace.exact_soft, "EXACT_TILE_PIXELS", 1 << 20)
    monkeypatch.setattr(raytrace.exact_soft, "TILE_PIXELS_LEAST", 1 << 20)
    want = exact_visibility(scene)
    for rows in (2, 3, 6):
        monkeypatch.setattr(raytrace.exact_soft, "EXACT_TILE_PIXELS", rows * scene.width)
        got = exact_visibility(scene)
        assert got.visibility.tobytes() == want.visibility.tobytes()
        assert got.irradiance.tobytes() == want.irradiance.tobytes()
    step = [stop - start for start, stop in traced[2][:-1]]
    assert set(step) == {4} and len(traced[1]) == 12 and len(traced[3]) == 4


def _measured(chain: np.ndarray, light) -> float:
    """The area inside the convex polygon `light` of the region a boundary (e, 2, 2) (the
    region on each piece's left) bounds: its fan of signed triangles from the light's first
    corner, each cut to the light by shapely."""
    c = np.asarray(light.exterior.coords)[0]
    total = 0.0
    for a, b in chain:
        signed = (a[0] - c[0]) * (b[1] - c[1]) - (a[1] - c[1]) * (b[0] - c[0])
        if signed != 0:
            total += np.sign(signed) * shapely.Polygon([c, a, b]).intersection(light).area
    return total


@pytest.mark.parametrize("seed", range(8))
def test_an_outline_cut_to_a_box_measures_as_shapelys_union(seed):
    """Folded sheets and loose triangles: each pixel's boundary cut to a box (the windings
    kernel with `box`) and whole (without) measure inside a light within the box as shapely's
    union of the triangles does; the cut one has its pieces within the box."""
    rng = np.random.default_rng(seed)
    pixels = [sheet(rng, 6, 0.35), loose(rng), sheet(rng, 4, 0.6)]
    box = np.array([0.9, 0.7, 2.6, 2.9]) + rng.uniform(-0.3, 0.3, 4)
    light = shapely.Polygon([box[:2] + 0.05, [box[2] - 0.05, box[1] + 0.05],
                             box[2:] - 0.05, [box[0] + 0.05, box[3] - 0.05]])
    uncut = np.concatenate([t for t, _ in pixels])
    ids = np.concatenate([i + 1000 * k for k, (_, i) in enumerate(pixels)])
    owner = np.repeat(np.arange(len(pixels)), [len(t) for t, _ in pixels])
    free = np.ones(len(uncut), bool)
    whole = windings.boundaries(uncut, free, ids, owner, len(pixels))
    cut = windings.boundaries(uncut, free, ids, owner, len(pixels), box=box)
    certain = 0
    for k, (tris, _) in enumerate(pixels):
        if cut[k] is None or whole[k] is None:
            continue
        certain += 1
        union = shapely.union_all([shapely.Polygon(t) for t in tris
                                   if shapely.Polygon(t).area > 0])
        want = union.intersection(light).area
        assert abs(_measured(cut[k], light) - want) <= 1e-12 * max(1.0, want)
        assert abs(_measured(whole[k], light) - want) <= 1e-12 * max(1.0, want)
        ends = cut[k].reshape(-1, 2)
        assert (ends >= box[:2] - 1e-12).all() and (ends <= box[2:] + 1e-12).all()
    assert certain >= 2


def test_convex_bodies_and_a_floor_keep_the_pixel_by_pixel_bytes(monkeypatch):
    """scenes/soft.toml (a sphere, two boxes: convex, their shadows hulls; and a floor of two
    triangles): no block takes its pixels, so the bytes are the pixel-by-pixel path's."""
    from raytrace.exact_soft import exact_visibility
    from shadowvol.scenefile import load_scene
    scene = load_scene(SCENES / "soft.toml").replace(width=32, height=24)
    got = exact_visibility(scene)
    monkeypatch.setattr(raytrace.exact_soft, "BLOCK", 0)
    want = exact_visibility(scene)
    assert got.visibility.tobytes() == want.visibility.tobytes()
    assert got.irradiance.tobytes() == want.irradiance.tobytes()


def _tilted_light(rng, seed: int):
    """A rect (even seeds) or disk light 3 above the origin, tilted at random, in its frame,
    and its corners (k, 3)."""
    from raytrace.lightshapes import frame_light
    from shadowvol.scene import AreaLight
    shape = ("rect", "disk")[seed % 2]
    size = {"size": [1.2, 0.8]} if shape == "rect" else {"radius": 0.6}
    light = frame_light(AreaLight(shape, [0.0, 3.0, 0.0], normal=rng.normal([0, -1, 0], 0.2),
                                  samples=4, **size), np.zeros(3), "l")
    return light, light.center + light.hull @ light.axes


@pytest.mark.parametrize("seed", range(8))
def test_a_blocks_near_test_keeps_every_triangle_that_meets_a_pixels_pyramid(seed):
    """`blockkernels._near` (one pixel's side planes lowered by the block's slack) keeps
    every triangle that meets some pixel's pyramid, against a float64 witness: a point of the
    triangle found inside that pyramid (its side planes and the light's plane), the triangles
    from a metre down to 1e-9 across, some reaching in by a hair over a side; and it leaves
    out triangles well outside every pyramid (it can fail)."""
    from raytrace import blockkernels, pyramid
    rng = np.random.default_rng(seed)
    light, base = _tilted_light(rng, seed)
    corner = rng.uniform(-1, 1, 3) * [1, 0.2, 1]
    p = corner + rng.normal(0, 0.01 * 10.0 ** -rng.integers(0, 4), (4, 3))   # a block
    sides = np.stack([m / np.linalg.norm(m, axis=1, keepdims=True)
                      for m in pyramid.sides(light, p, base)])
    slack = np.empty(len(sides))
    blockkernels._slacks(0, 4, p, sides, slack)

    def inside(x, k):
        return (sides[:, k] @ (x - p[k]) >= 0).all() and (x - light.center) @ light.normal >= 0

    def near(tri):
        packed = np.zeros((1, 1, 16))
        packed[0, 0, :3], packed[0, 0, 3:6] = tri.min(axis=0), tri.max(axis=0)
        return blockkernels._near(0, 0, 0, packed, p, sides, slack)

    kept = left = 0
    weights = np.array([[a, b, 1 - a - b] for a in np.linspace(0, 1, 5)
                        for b in np.linspace(0, 1 - a, 5)])
    for _ in range(300):
        k = int(rng.integers(0, 4))
        t = rng.uniform(0.05, 0.95)
        y = base[rng.integers(0, len(base))] * 0.999 + light.center * 0.001
        x = p[k] + t * (y - p[k])                       # in pixel k's pyramid, near a side
        size = 10.0 ** rng.uniform(-9, 0)
        tri = x + rng.normal(0, size, (3, 3))
        if any(inside(w @ tri, k) for w in weights):
            kept += 1
            assert near(tri), (tri, k)
        far = p[k] + 3 * (x - light.center) + rng.normal(0, 0.01, (3, 3))  # well outside
        if not any(inside(w @ far, j) for w in weights for j in range(4)):
            left += not near(far)
    assert kept > 100 and left > 100


@pytest.mark.parametrize("seed", range(6))
def test_a_pair_left_out_outside_a_pyramid_is_so_exactly(seed):
    """`exactkernels._outside` (a block's free unsteady triangle left out of a pixel's pairs)
    holds only where every corner lies outside one side plane of the pixel's pyramid, by
    exact rational arithmetic on the floats (the plane through p and two of the light's
    corners, turned toward its centre), for triangles lying along a side plane a hair (1e-6
    down to 1e-19 of their distance) either side of it; and it holds for every triangle
    outside by more than 1e-9 of that (it can fail both ways)."""
    from fractions import Fraction
    from raytrace import exactkernels, pyramid
    rng = np.random.default_rng(seed)
    light, base = _tilted_light(rng, seed)
    p = rng.uniform(-1, 1, (1, 3)) * [1, 0.2, 1]
    sides = np.stack([m / np.linalg.norm(m, axis=1, keepdims=True)
                      for m in pyramid.sides(light, p, base)])
    exact = [[Fraction(v) for v in row] for row in (p[0], light.center)]

    def outside_exactly(tri, j):
        a, b = ([Fraction(v) - exact[0][x] for x, v in enumerate(base[i])]
                for i in (j, (j + 1) % len(base)))
        n = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        if sum(n[x] * (exact[1][x] - exact[0][x]) for x in range(3)) < 0:
            n = [-v for v in n]
        return all(sum(n[x] * (Fraction(c[x]) - exact[0][x]) for x in range(3)) < 0
                   for c in tri)

    dropped = far = 0
    for _ in range(400):
        j = int(rng.integers(0, len(base)))
        a, b = base[j] - p[0], base[(j + 1) % len(base)] - p[0]
        # corners in side plane j (beyond the light or short of it), moved off it
        w = rng.uniform(-0.5, 1.5, (3, 2)) * rng.uniform(0.1, 2.0, (3, 1))
        on = p[0] + w[:, :1] * a + w[:, 1:] * b
        dist = np.linalg.norm(on - p[0], axis=1, keepdims=True)
        off = 10.0 ** rng.uniform(-19, -6) * rng.choice([-1, 1])
        tri = on + off * dist * sides[j, 0] * rng.uniform(0.5, 1.0, (3, 1))
        got = exactkernels._outside(0, 0, p, tri[None], sides)
        if got:
            dropped += 1
            assert any(outside_exactly(tri, k) for k in range(len(base))), (tri, off)
        if off < -1e-9:
            far += 1
            assert got, (tri, off)
    assert dropped > 50 and far > 20


def test_a_blocks_own_candidates_are_the_numpy_pairs(monkeypatch):
    """`exactkernels.own_candidates` (the pixels' pairs of their blocks' unsteady triangles,
    in numba) gives the pairs of numpy's composition of `candidates._keep` that it replaced,
    in the same order, on the sheet, the ball and the floor: among those left out are the
    floor's other triangle (coplanar with a pixel's own), triangles whose boxes miss the
    pixel's pyramid's, those the one-way rule leaves out (turned away from the pixel) and
    those wholly outside a side plane of its pyramid."""
    from raytrace import blockkernels, exactkernels
    from raytrace.candidates import _keep
    from raytrace.exact_soft import exact_visibility
    calls = []
    kernel = exactkernels.own_candidates

    def spy(*args):
        got = kernel(*args)
        calls.append((args, got))
        return got

    monkeypatch.setattr(polygons.kernels("blockkernels"), "own_candidates", spy)
    objects = []
    real = raytrace.blockwindings._own_pairs

    def own_pairs(light, objs, corners, p, *rest):
        objects.append((objs, corners, p))
        return real(light, objs, corners, p, *rest)

    monkeypatch.setattr(raytrace.blockwindings, "_own_pairs", own_pairs)
    # the tiles one after another, so the two spies' calls pair up
    monkeypatch.setattr(raytrace.exact_soft, "for_each_tile",
                        lambda work, tiles, tracer: [work(tile) for tile in tiles])
    exact_visibility(_scene("rect", 16))
    assert calls and len(calls) == len(objects)
    coplanar = missed = dropped = outside = 0
    for (args, got), (objs, corners, p) in zip(calls, objects):
        block, unsteady, to_cut, u_at, own, _, _, lo, hi = args[:9]
        many = np.diff(u_at)[block]
        pix = np.repeat(np.arange(len(p)), many)
        first = np.repeat(u_at[block] - np.r_[0, np.cumsum(many)[:-1]], many) + \
            np.arange(len(pix))
        # those the one-way rule leaves out: free from every pixel of the block, turned away
        # from this one by more than FACING of the distance (`exactkernels.own_candidates`)
        rel = p[pix] - corners[unsteady[first], 0]
        away = args[-2][first] & ~to_cut[first] & (polygons.dot(
            objs.normal[unsteady[first]], rel) < -blockkernels.FACING * np.linalg.norm(rel, axis=1))
        dropped += int(away.sum())
        # and those wholly outside a side plane of the pixel's pyramid (`_outside`: each
        # corner below it by more than 2^-40 of its L1 distance from p)
        r = corners[unsteady[first]] - p[pix][:, None]                    # (q, 3, 3)
        m = args[-1][:, pix, None]                                          # (s, q, 1, 3)
        # the kernel's sums, left to right
        below = m[..., 0] * r[..., 0] + m[..., 1] * r[..., 1] + m[..., 2] * r[..., 2] < \
            -2.0 ** -40 * (np.abs(r[..., 0]) + np.abs(r[..., 1]) + np.abs(r[..., 2]))
        out = ~to_cut[first] & ~away & below.all(axis=2).any(axis=0)
        outside += int(out.sum())
        pix, first = pix[~(away | out)], first[~(away | out)]
        tri, free = unsteady[first], ~to_cut[first]
        assert np.array_equal(got[0], pix[free]) and np.array_equal(got[1], tri[free])
        pix, tri = pix[~free], tri[~free]
        near = tri != own[pix]
        for a in range(3):
            near &= (objs.tri_lo[tri, a] <= hi[pix, a]) & (objs.tri_hi[tri, a] >= lo[pix, a])
        missed += int((~near).sum())
        pix, tri = pix[near], tri[near]
        # no convex object's triangle comes here (the kernel leaves out `_keep`'s rule for
        # them): the pixels' normals do not matter
        assert not objs.convex[tri].any()
        keep = _keep(objs, corners, p, np.zeros_like(p), own, pix, tri, None)
        flat = np.abs(polygons.dot(objs.normal[own[pix]], objs.normal[tri])) > 1 - 1e-3
        coplanar += int((flat & ~keep).sum())
        assert np.array_equal(got[2], pix[keep]) and np.array_equal(got[3], tri[keep])
    assert coplanar > 0 and missed > 0 and dropped > 0 and outside > 0


@pytest.mark.parametrize("shape", ["rect", "disk"])
def test_the_rims_carried_to_the_box_give_the_whole_rims_chains(shape, monkeypatch):
    """`blockkernels.carried_edges` carries only the edges that meet the light's box or
    cross the level of its first corner: `windings.boundaries` cut to the box (partial) gives
    each pixel the chain it gives with every edge carried, bit for bit, or leaves it in
    doubt (None) where the cut is (there the whole outline was the way out); and an edge
    that crosses that level outside the box is needed (the winding at the corner)."""
    from raytrace import blockkernels
    from raytrace.exact_soft import exact_visibility
    kernel, calls = blockkernels.carried_edges, []

    def spy(*args):
        calls.append(args)
        return kernel(*args)

    monkeypatch.setattr(polygons.kernels("blockkernels"), "carried_edges", spy)
    monkeypatch.setattr(raytrace.exact_soft, "for_each_tile",
                        lambda work, tiles, tracer: [work(tile) for tile in tiles])
    boundaries, wound = windings.boundaries, []

    def spy_boundaries(*args, **kw):
        wound.append((args, kw))
        return boundaries(*args, **kw)

    monkeypatch.setattr(windings, "boundaries", spy_boundaries)
    exact_visibility(_scene(shape, 20))
    wound = [w for w in wound if w[1].get("partial")]
    assert calls and len(calls) == len(wound)
    same = doubt = crossing = 0
    for args, (b_args, kw) in zip(calls, wound):
        box = args[-1]
        every = kernel(*args[:-1], np.array([-np.inf, -np.inf, np.inf, np.inf]))
        assert len(every[0]) == sum(len(range(args[5][b], args[5][b + 1])) *
                                    (args[0][b + 1] - args[0][b])
                                    for b in range(len(args[0]) - 1))
        old = boundaries(*b_args, rims=every, box=box)
        new = boundaries(*b_args, rims=kernel(*args), box=box, partial=True)
        for o, g in zip(old, new):
            if g is None:
                doubt += 1
            else:
                assert o is not None and o.tobytes() == g.tobytes()
                same += 1
        flat = every[0]
        apart = (np.minimum(flat[:, 0, 0], flat[:, 1, 0]) > box[2]) | \
            (np.maximum(flat[:, 0, 0], flat[:, 1, 0]) < box[0]) | \
            (np.minimum(flat[:, 0, 1], flat[:, 1, 1]) > box[3]) | \
            (np.maximum(flat[:, 0, 1], flat[:, 1, 1]) < box[1])
        level = (flat[:, 0, 1] <= box[1]) != (flat[:, 1, 1] <= box[1])
        crossing += int((apart & level).sum())
    assert same > 100 and doubt <= same // 50 and crossing > 0


def test_a_cut_in_doubt_with_partial_rims_is_in_doubt():
    """A shadow whose edge runs through the box's first corner (the winding there is not
    certain): cut to the box with every edge at hand, `boundaries` outlines it whole; with
    `partial` (the rims carried to the box only) it leaves the pixel in doubt."""
    box = np.array([0.0, 0.0, 1.0, 1.0])
    uncut = np.array([[[-0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]]])
    args = (uncut, np.ones(1, bool), np.array([[0, 1, 2]]), np.zeros(1, np.int64), 1)
    whole = windings.boundaries(*args, box=box)[0]
    assert whole is not None and len(whole) == 3
    assert windings.boundaries(*args, box=box, partial=True)[0] is None


def _floor(size: int):
    """A floor (y = 0) seen from 4 up and 1 back under a 1 x 1 rect light 3 up: every pixel
    on it."""
    from shadowvol.primitives import plane
    from shadowvol.scene import AreaLight, Camera, Material, Scene
    light = AreaLight("rect", [0.3, 3.0, 0.0], normal=[0, -1, 0], size=[1.0, 1.0], samples=4)
    return Scene(camera=Camera(eye=[0.0, 4.0, 1.0], target=[0.0, 0.0, 0.0], fov_y=40.0),
                 objects=[plane("floor", point=(0, 0, 0), size=[40, 40],
                                material=Material(diffuse=[0.8, 0.8, 0.8]))],
                 lights=[light], width=size, height=size, ambient=[0, 0, 0])


def _grids(scene, origin):
    """The frame's float32 and float64 `RayGrid`s in the backend's frame (as
    `exact_visibility` makes them)."""
    import dataclasses
    from raytrace.camera import RayGrid
    camera = dataclasses.replace(scene.camera, eye=scene.camera.eye - origin,
                                 target=scene.camera.target - origin)
    return tuple(RayGrid(camera, scene.width, scene.height, t) for t in (np.float32, np.float64))


def _pairs(scene, backend):
    """`exact_soft.neighbours` of the frame (as `exact_visibility` traces them)."""
    tracer, triangles, origin = backend
    return raytrace.exact_soft.neighbours(tracer, triangles, _grids(scene, origin),
                                          scene.height)


def _footprint_of(scene, backend):
    """`exact_soft.footprint` of the scene's light, and the same median taken over every
    pair of neighbours in a row, each pixel-centre ray met with the floor's plane in float64
    by numpy here (the witness)."""
    from raytrace.camera import RayGrid
    from raytrace.lightshapes import frame_light
    got = raytrace.exact_soft.footprint(
        frame_light(scene.lights[0], backend.origin, "lights[0]"), _pairs(scene, backend))
    grid = RayGrid(scene.camera, scene.width, scene.height, np.float64)
    v = grid.directions().T.reshape(scene.height, scene.width, 3)
    p = grid.eye + v * (-grid.eye[1] / v[..., 1:2])
    step = np.linalg.norm(np.diff(p, axis=1), axis=2)
    far = np.linalg.norm(p[:, :-1] - scene.lights[0].center, axis=2)
    return got, float(np.median(step / far))


@pytest.mark.parametrize("size", [32, 96, 256, 512])
def test_finer_frames_take_larger_blocks(size, monkeypatch):
    """`exact_soft.block_side`: BLOCK, one more under each of FINE of the frame's footprint
    (a point's distance from its right neighbour's over its distance from the light's centre,
    the median over a few rows), here against the median over every pixel of a floor seen
    from above (numpy's points, `_footprint_of`): within 2 %, and the side the rule gives
    (the sizes' footprints lie 20 % or more from FINE's); BLOCK 0 stays 0."""
    from raytrace.lightshapes import frame_light
    from raytrace.masks import scene_backend
    scene = _floor(size)
    backend = scene_backend(scene)
    got, want = _footprint_of(scene, backend)
    assert abs(got / want - 1) < 0.02, (got, want)
    fine = raytrace.exact_soft.FINE
    assert all(abs(np.log(want / f)) > np.log(1.2) for f in fine)
    # the rule on the footprint found
    monkeypatch.setattr(raytrace.exact_soft, "footprint", lambda *args: got)
    light = frame_light(scene.lights[0], backend.origin, "lights[0]")

    def side():
        return raytrace.exact_soft.block_side(light, None)
    assert side() == raytrace.exact_soft.BLOCK + sum(want < f for f in fine)
    assert side() == {32: 2, 96: 2, 256: 3, 512: 4}[size]
    monkeypatch.setattr(raytrace.exact_soft, "BLOCK", 0)
    assert side() == 0


@pytest.mark.parametrize("view", ["away", "one column"])
def test_no_neighbours_no_footprint(view):
    """No two neighbours in a row covered (the camera turned away from the floor, or a frame
    one pixel wide: a row's last pixel is no neighbour of the next row's first): the
    footprint is inf, and the blocks BLOCK a side."""
    from raytrace.lightshapes import frame_light
    from raytrace.masks import scene_backend
    from shadowvol.scene import Camera
    scene = _floor(32).replace(width=1) if view == "one column" else _floor(32).replace(
        camera=Camera(eye=[0.0, 4.0, 1.0], target=[0.0, 9.0, 0.0], fov_y=40.0))
    backend = scene_backend(scene)
    light = frame_light(scene.lights[0], backend.origin, "lights[0]")
    pairs = _pairs(scene, backend)
    assert len(pairs[0]) == len(pairs[1]) == 0
    assert raytrace.exact_soft.footprint(light, pairs) == np.inf
    assert raytrace.exact_soft.block_side(light, pairs) == raytrace.exact_soft.BLOCK


@pytest.mark.parametrize("seed", range(6))
def test_chunks_hold_whole_bands_of_blocks(seed, monkeypatch):
    """`exact_soft._chunks`: the tile's covered pixels in order, each chunk from the start of
    a band of `block` rows (a band never in two chunks), no more chunks than CHUNK_PIXELS
    makes and none longer than CHUNK_PIXELS and a band; slices of CHUNK_PIXELS where block
    is 0."""
    rng = np.random.default_rng(seed)
    monkeypatch.setattr(raytrace.exact_soft, "CHUNK_PIXELS", int(rng.integers(5, 300)))
    chunk = raytrace.exact_soft.CHUNK_PIXELS
    width = int(rng.integers(1, 90))
    pixel = np.flatnonzero(rng.random(width * int(rng.integers(1, 60))) < rng.uniform(0.05, 1))
    for block in (0, 1, 2, 3, 4):
        parts = raytrace.exact_soft._chunks(pixel, width, block)
        assert np.array_equal(np.concatenate([np.arange(len(pixel))[s] for s in parts]
                                             or [np.zeros(0, int)]), np.arange(len(pixel)))
        sizes = [len(pixel[s]) for s in parts]
        if block == 0:
            assert sizes[:-1] == [chunk] * (len(parts) - 1)
            continue
        band = pixel // width // block
        assert all(s.start == 0 or band[s.start] != band[s.start - 1] for s in parts)
        longest = np.bincount(band).max(initial=0)
        assert len(parts) <= -(-len(pixel) // chunk) and max(sizes, default=0) <= chunk + longest


def test_tiles_of_whole_larger_blocks_give_the_same_bytes(monkeypatch):
    """Blocks of 3 (FINE made to take one more on any frame): the tiles are whole bands of
    3 rows (2 and 4 rows asked for make 3 and 6, 6 makes 6), they give the same bytes, and
    the pixel-by-pixel measures to rounding."""
    from raytrace.exact_soft import exact_visibility
    scene = _scene("rect", 24)
    monkeypatch.setattr(raytrace.exact_soft, "BLOCK", 0)
    plain = exact_visibility(scene)
    monkeypatch.setattr(raytrace.exact_soft, "BLOCK", 2)
    monkeypatch.setattr(raytrace.exact_soft, "FINE", (np.inf,))
    traced, sides = _traced_tiles(monkeypatch), []
    side = raytrace.exact_soft.block_side
    monkeypatch.setattr(raytrace.exact_soft, "block_side",
                        lambda *args: sides.append(side(*args)) or sides[-1])
    chains, taken = raytrace.blockwindings.chains, set()

    def blocks(*args, **kwargs):
        taken.add(args[8])
        return chains(*args, **kwargs)
    monkeypatch.setattr(raytrace.blockwindings, "chains", blocks)
    monkeypatch.setattr(raytrace.exact_soft, "TILE_PIXELS_LEAST", 1 << 20)
    got = []
    for rows in (2, 4, 6):
        monkeypatch.setattr(raytrace.exact_soft, "EXACT_TILE_PIXELS", rows * scene.width)
        got.append(exact_visibility(scene))
    assert sides == [3, 3, 3] and taken == {3}
    assert [{b - a for a, b in t[:-1]} for t in traced] == [{3}, {6}, {6}]
    for each in got[1:]:
        assert each.visibility.tobytes() == got[0].visibility.tobytes()
        assert each.irradiance.tobytes() == got[0].irradiance.tobytes()
    assert np.abs(got[0].visibility - plain.visibility).max() <= ROUNDING
    assert np.abs(got[0].irradiance - plain.irradiance).max() <= ROUNDING
