"""The two triangle backends (numpy float64 reference, Embree float32) give the same answers, and
a ray leaving a surface with the shadow-ray offset never hits that surface again."""

import warnings

import numpy as np
import pytest

from raytrace.backends import EmbreeBackend, NumpyBackend, make_backend
from raytrace.tolerances import EDGE_AGREEMENT_RELATIVE, length_scale, surface_offset
from shadowvol.primitives import mesh
from shadowvol.scene import Camera, PointLight, Scene


def random_soup(rng, m=1500, spread=2.0, size=0.3, centre=(0.0, 0.0, 0.0)):
    """m random triangles around `centre`: vertices (3m, 3), faces (m, 3)."""
    c = rng.uniform(-spread, spread, (m, 1, 3)) + np.asarray(centre)
    tri = c + rng.normal(scale=size, size=(m, 3, 3))
    return tri.reshape(-1, 3), np.arange(3 * m).reshape(-1, 3)


def soup_scene(vertices, faces, eye=(0.0, 0.0, 10.0)):
    return Scene(camera=Camera(eye=list(eye), target=list(np.mean(vertices, axis=0))),
                 objects=[mesh("soup", vertices, faces)], lights=[PointLight([0, 10, 0])])


def random_rays(rng, n, spread=3.0):
    o = rng.uniform(-spread, spread, (n, 3))
    d = rng.normal(size=(n, 3))
    return o, d / np.linalg.norm(d, axis=1, keepdims=True)


def edge_distance(points, tri):
    """Distance (n,) from points (n, 3) to the nearest edge of triangles tri (n, 3, 3)."""
    best = np.full(len(points), np.inf)
    for i, j in ((0, 1), (1, 2), (2, 0)):
        a, b = tri[:, i], tri[:, j]
        ab = b - a
        s = np.clip(np.einsum("ij,ij->i", points - a, ab) / np.einsum("ij,ij->i", ab, ab), 0, 1)
        best = np.minimum(best, np.linalg.norm(points - (a + s[:, None] * ab), axis=1))
    return best


def test_backends_agree_on_closest_hits():
    rng = np.random.default_rng(2024)
    v, f = random_soup(rng)
    scene = soup_scene(v, f)
    ref, emb = NumpyBackend(v, f), EmbreeBackend(v, f)
    o, d = random_rays(rng, 20000)
    # A tenth of the rays aim exactly at edge midpoints, where the two may rightly differ.
    tris = v[f]
    aim = tris[rng.integers(0, len(f), 2000)]
    aim = (aim[:, 0] + aim[:, 1]) / 2
    d[:2000] = aim - o[:2000]
    d[:2000] /= np.linalg.norm(d[:2000], axis=1, keepdims=True)
    h_ref, h_emb = ref.closest_hit(o, d), emb.closest_hit(o, d)
    assert 0.2 < np.mean(h_ref.tri >= 0) < 0.9  # the scene is neither empty nor a wall
    differ = h_ref.tri != h_emb.tri
    # Where they differ, float32 had to decide at an edge: the ray passes within
    # EDGE_AGREEMENT_RELATIVE of the length scale of an edge of the triangle one of them hit
    # (the other then sees past that edge, to a triangle behind or to nothing).
    tolerance = EDGE_AGREEMENT_RELATIVE * length_scale(scene)
    near_edge = np.zeros(len(o), bool)
    for hits in (h_ref, h_emb):
        k = np.flatnonzero(differ & (hits.tri >= 0))
        p = o[k] + hits.t[k, None] * d[k]
        near_edge[k] |= edge_distance(p, tris[hits.tri[k]]) < tolerance
    assert near_edge[differ].all(), f"{(~near_edge[differ]).sum()} rays disagree away from edges"
    assert differ.sum() <= 0.05 * 2000  # and that is rare even there
    same = ~differ & (h_ref.tri >= 0)
    # Same triangle: the same t, both refined in float64 against that triangle's plane.
    assert np.array_equal(h_ref.t[same], h_emb.t[same])
    assert np.all(np.isinf(h_emb.t[h_emb.tri < 0]))


def test_backends_agree_on_bounded_occlusion():
    rng = np.random.default_rng(99)
    v, f = random_soup(rng)
    scene = soup_scene(v, f)
    ref, emb = make_backend("numpy", v, f), make_backend("embree", v, f)
    o, d = random_rays(rng, 20000)
    tmax = rng.uniform(0.0, 4.0, len(o))
    occ_ref, occ_emb = ref.occluded(o, d, tmax), emb.occluded(o, d, tmax)
    hits = ref.closest_hit(o, d)
    # Bounded: occluded exactly when the nearest hit lies before tmax.
    expect = hits.t < tmax
    tol = EDGE_AGREEMENT_RELATIVE * length_scale(scene)
    for occ in (occ_ref, occ_emb):
        bad = occ != expect
        # ... except where the nearest hit is within float32 reach of tmax or of an edge.
        p = o[bad] + np.minimum(hits.t[bad], tmax[bad])[:, None] * d[bad]
        k = hits.tri[bad]
        excusable = (np.abs(hits.t[bad] - tmax[bad]) < tol) | (
            (k >= 0) & (edge_distance(p, v[f][np.maximum(k, 0)]) < tol))
        assert excusable.all() and bad.sum() <= 5
    assert 0.1 < occ_ref.mean() < 0.9
    # Unbounded, and one direction shared by every ray.
    up = np.array([[0.0, 1.0, 0.0]])
    assert np.array_equal(ref.occluded(o, up), emb.occluded(o, up))
    assert np.array_equal(emb.occluded(o, up), emb.occluded(o, np.repeat(up, len(o), axis=0)))


def test_embree_thread_split_changes_nothing():
    rng = np.random.default_rng(5)
    v, f = random_soup(rng)
    emb = EmbreeBackend(v, f)
    o, d = random_rays(rng, 50000)
    assert np.array_equal(emb.closest_triangle(o, d, parallel=True),
                          emb.closest_triangle(o, d, parallel=False))


def test_without_packets_embree_falls_back_to_single_rays_said_once(monkeypatch):
    """numba or the library missing: the "embree" backend is embreex's single rays, and the
    process is told once; asked for by name, the packets' absence is a MissingExtra."""
    from raytrace import embree
    from shadowvol.errors import MissingExtra
    monkeypatch.setattr(embree, "_packets_missing", lambda: "numba: No module named 'numba'")
    monkeypatch.setattr(embree, "_fallback_said", [])
    monkeypatch.delenv("SHADOWVOL_EMBREE", raising=False)
    v, f = random_soup(np.random.default_rng(0), m=4)
    with pytest.warns(RuntimeWarning, match="packet queries unavailable .*numba"):
        assert type(make_backend("embree", v, f)) is EmbreeBackend
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert type(make_backend("embree", v, f)) is EmbreeBackend   # said once
    monkeypatch.setenv("SHADOWVOL_EMBREE", "packets")
    with pytest.raises(MissingExtra, match=r"shadowvol\[fast\]"):
        make_backend("embree", v, f)


def test_unknown_backend():
    v, f = random_soup(np.random.default_rng(0), m=2)
    with pytest.raises(ValueError, match="unknown backend 'optix'"):
        make_backend("optix", v, f)


@pytest.mark.parametrize("backend", ["numpy", "embree"])
@pytest.mark.parametrize("centre", [(0.0, 0.0, 0.0), (900.0, -300.0, 500.0)])
def test_a_ray_leaving_a_surface_never_hits_it_again(backend, centre):
    """Seeded property: from a random point of a random triangle, offset along the normal by
    `surface_offset`, any direction into that side (down to grazing ones) misses the triangle
    it left.  Far from the origin (second case) float32 coordinates are coarse: the offset
    scales with the largest coordinate, not only the scene's extent."""
    rng = np.random.default_rng(11)
    v, f = random_soup(rng, m=400, spread=1.0, size=0.2, centre=centre)
    scene = soup_scene(v, f, eye=np.asarray(centre) + [0.0, 0.0, 5.0])
    tracer = make_backend(backend, v, f)
    n = 20000
    k = rng.integers(0, len(f), n)
    tri = v[f[k]]
    bary = rng.dirichlet([1, 1, 1], n)
    p = np.einsum("nk,nkj->nj", bary, tri)
    normal = tracer.normals[k] * rng.choice([-1.0, 1.0], (n, 1))  # either side
    # Directions in the hemisphere of `normal`, a fifth of them within 1e-3 rad of grazing.
    d = rng.normal(size=(n, 3))
    d -= np.einsum("ij,ij->i", d, normal)[:, None] * normal
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    elevation = np.where(rng.random(n) < 0.2, rng.uniform(1e-6, 1e-3, n),
                         rng.uniform(0, np.pi / 2, n))
    d = np.cos(elevation)[:, None] * d + np.sin(elevation)[:, None] * normal
    start = p + surface_offset(scene) * normal
    hits = tracer.closest_hit(start, d)
    assert not np.any(hits.tri == k), f"{np.sum(hits.tri == k)} rays hit their own triangle"
