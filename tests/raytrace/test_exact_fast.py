"""The fast path of the exact visibility (`raytrace.exact_soft`) against its plain float64
reference, the union of every triangle's shadow one by one: crowded pixels' unions taken from
their outline (`raytrace.arrange`) or measured from its windings (`raytrace.windings`), on random scenes of closed (a noisy ball, wound either way), open (a
bowl, a sheet) and non-manifold (fins on one edge) casters, each standing on the floor (contact
shadows) or floating, under rect, disk and polygon lights.  The same V and irradiance to
ROUNDING (the two differ by GEOS's snapping of different pieces, ~1e-14), where the fast path
was used on many pixels.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from builders import FLOOR_Y, LIGHT_Y, MATTE

import raytrace.arrange
import raytrace.exact_soft
import raytrace.windings
from raytrace.exact_soft import exact_visibility
from shadowvol.primitives import mesh, plane
from shadowvol.scene import AreaLight, Camera, Scene

ROUNDING = 1e-12


def _ball(rng, radius):
    import trimesh
    ico = trimesh.creation.icosphere(subdivisions=2, radius=radius)
    v = ico.vertices * (1 + 0.15 * rng.standard_normal((len(ico.vertices), 1)))
    return v, np.asarray(ico.faces)


def _random_scene(seed: int, size: int = 24) -> Scene:
    rng = np.random.default_rng(seed)
    kind = ("rect", "disk", "polygon")[seed % 3]
    centre = [rng.uniform(-0.4, 0.4), LIGHT_Y, rng.uniform(-0.4, 0.4)]
    normal = [rng.uniform(-0.3, 0.3), -1, rng.uniform(-0.3, 0.3)]
    if kind == "rect":
        light = AreaLight("rect", centre, normal=normal, size=rng.uniform(0.6, 1.4, 2), samples=4)
    elif kind == "disk":
        light = AreaLight("disk", centre, normal=normal, radius=rng.uniform(0.3, 0.7), samples=4)
    else:   # a star, not convex, in a horizontal plane
        r = np.where(np.arange(10) % 2, 0.3, 0.7)
        a = np.arange(10) * math.pi / 5
        light = AreaLight("polygon", None, vertices=np.c_[r * np.cos(a), np.full(10, LIGHT_Y),
                                                          r * np.sin(a)] + [centre[0], 0, 0],
                          samples=4)
    objects = [plane("floor", point=[0.0, FLOOR_Y, 0.0], size=[8.0, 8.0], material=MATTE)]
    # closed, not convex: a noisy ball, on the floor or floating, wound either way
    v, f = _ball(rng, rng.uniform(0.3, 0.5))
    lift = -v[:, 1].min() + (0 if rng.random() < 0.5 else rng.uniform(0.2, 0.8))
    objects.append(mesh("ball", v + [rng.uniform(-1, 1), lift, rng.uniform(-1, 1)],
                        f if rng.random() < 0.5 else f[:, ::-1], MATTE))
    # open: the ball's lower half (a bowl) with its rim on the floor or floating, and a
    # bumpy sheet of a grid of triangles
    v, f = _ball(rng, rng.uniform(0.3, 0.5))
    bowl = f[v[f].mean(axis=1)[:, 1] < 0.05]
    v = v * [1, -1, 1]
    lift = -v[bowl].reshape(-1, 3)[:, 1].min() + (0 if rng.random() < 0.5 else 0.4)
    objects.append(mesh("bowl", v + [rng.uniform(-1, 1), lift, rng.uniform(-1, 1)],
                        bowl[:, ::-1], MATTE))
    n = 8
    x, z = np.meshgrid(np.linspace(-0.5, 0.5, n), np.linspace(-0.5, 0.5, n))
    y = 0.12 * rng.standard_normal((n, n)) + rng.uniform(0.8, 1.5)
    grid = np.c_[x.ravel(), y.ravel(), z.ravel()] + [rng.uniform(-1, 1), 0, rng.uniform(-1, 1)]
    k = np.arange(n * n).reshape(n, n)[:-1, :-1].ravel()
    quads = np.c_[k, k + 1, k + n + 1, k + n]
    objects.append(mesh("sheet", grid, np.r_[quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]], MATTE))
    # non-manifold: three fins on one edge, standing on the floor
    spine = np.array([[0, 0, -0.3], [0, 0.6, 0.3]]) + [rng.uniform(-1, 1), FLOOR_Y,
                                                       rng.uniform(-1, 1)]
    fins = np.vstack([spine, spine.mean(0) + rng.uniform(-0.5, 0.5, (3, 3)) * [1, 0.3, 1]
                      + [0, 0.3, 0]])
    objects.append(mesh("fins", fins, [[0, 1, 2], [0, 1, 3], [1, 0, 4]], MATTE))
    camera = Camera(eye=[0.0, 4.5, 5.5], target=[0.0, 0.3, -0.3], fov_y=40.0)
    return Scene(camera=camera, objects=objects, lights=[light], width=size, height=size,
                 ambient=[0.0, 0.0, 0.0])


def _reference(scene, monkeypatch):
    with monkeypatch.context() as m:
        _crowded_from(m, 1 << 62)
        return exact_visibility(scene)


def _crowded_from(monkeypatch, many: int) -> None:
    """The outline's union (`raytrace.arrange`) and its windings (`raytrace.windings`) for a
    pixel of more than `many` shadows (1 << 62: neither, every shadow united one by one)."""
    monkeypatch.setattr(raytrace.exact_soft, "MANY_PIECES", many)
    monkeypatch.setattr(raytrace.exact_soft, "WINDING_PIECES", many)
    if many == 1 << 62:         # nor a block's shared outline (`raytrace.blockwindings`)
        monkeypatch.setattr(raytrace.exact_soft, "BLOCK", 0)


def _counted(monkeypatch, module, name):
    """Wrap module.name to count its calls (a list of their results)."""
    calls, plain = [], getattr(module, name)

    def counted(*args, **kwargs):
        got = plain(*args, **kwargs)
        calls.append(got)
        return got
    monkeypatch.setattr(module, name, counted)
    return calls


@pytest.mark.parametrize("seed", range(6))
def test_fast_paths_equal_the_triangle_by_triangle_union(seed, monkeypatch):
    scene = _random_scene(seed)
    slow = _reference(scene, monkeypatch)
    v = slow.visibility[0]
    assert ((v > 0) & (v < 1)).sum() > 40 and (v == 0).sum() > 5
    got = []
    wound = _counted(monkeypatch, raytrace.windings, "boundaries")
    for many in (None, 4):
        # the defaults, and crowded from 4 pieces: the outline on most shadowed pixels
        if many:
            _crowded_from(monkeypatch, many)
        got.append(exact_visibility(scene))
    # its windings on a rect or disk light (a polygon light's outline is not convex)
    assert sum(c is not None for got in wound for c in got) >= (10 if seed % 3 != 2 else 0)
    # the outline's union by GEOS (`raytrace.arrange`), the windings off
    monkeypatch.setattr(raytrace.windings, "boundaries",
                        lambda *args, **kwargs: np.full(args[4], None))
    arranged = _counted(monkeypatch, raytrace.arrange, "union")
    for many in (16, 4):
        _crowded_from(monkeypatch, many)
        got.append(exact_visibility(scene))
    assert len(arranged) >= 10
    for fast in got:
        assert np.abs(fast.visibility - slow.visibility).max() <= ROUNDING
        assert np.abs(fast.irradiance - slow.irradiance).max() <= ROUNDING


@pytest.mark.parametrize("batch", [1, 700])
def test_split_in_batches_of_any_size(batch, monkeypatch):
    """`windings.split` hands its pixels to `windings.boundaries` about BATCH shadows at a
    time (whole pixels): one pixel a batch, or a few, give the same bytes as the default
    (pixel by pixel: no block shares its outline, `raytrace.blockwindings`)."""
    scene = _random_scene(0)
    _crowded_from(monkeypatch, 4)
    monkeypatch.setattr(raytrace.exact_soft, "BLOCK", 0)
    wound = _counted(monkeypatch, raytrace.windings, "boundaries")
    want = exact_visibility(scene)
    calls = len(wound)                  # one a tile (`exact_soft`: a tile a thread at least)
    settled = sum(c is not None for got in wound for c in got)
    assert settled >= 10
    monkeypatch.setattr(raytrace.windings, "BATCH", batch)
    got = exact_visibility(scene)
    assert len(wound) - calls > calls
    assert sum(c is not None for got in wound[calls:] for c in got) == settled
    assert got.visibility.tobytes() == want.visibility.tobytes()
    assert got.irradiance.tobytes() == want.irradiance.tobytes()
