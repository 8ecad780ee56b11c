"""`windmeasures._less` in numba (`raytrace.measurekernels`) against its numpy path: each row's
convex region less the fan of signed triangles over its chain, each triangle clipped by the
clippers in turn, on random rows (several rows to a chain and up to four clippers, as the
inclusion and exclusion asks; clippers of no corners, fans that clip to nothing, edges of no
length, edges through the light's centre (no fan triangle), clockwise edges, corners on a
grid of sixteenths: ties on a clipper's edge) and through `exact_visibility` of a noisy ball;
and the probe of how numpy's matmul rounds (`windmeasures._matmul_mode`).

The areas are numpy's bytes.  The irradiance is numpy's bytes where numpy's `arctan2` is the
C library's atan2 (a CPU without AVX-512; here the witness's `np.arctan2` is made the C
library's for that test); numpy's own, SVML's under AVX-512, differs in the last bit now and
then, and the irradiance by at most ATAN2_SLACK.
"""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shadowcases import noisy_ball
from strategies import PROFILE, profile

from raytrace import polygons, windmeasures
from raytrace.lightshapes import FramedLight
from shadowvol.planes import default_plane_axes

pytest.importorskip("numba")

# |irradiance| (unit radiance) apart where one atan2 differs in its last bit: a row's terms
# are each at most pi / 2 (|n . unit(x0 x x1)| <= 1), one unit in the last place of theta
# moves one by at most ~4e-16, and the sums round alike but for that; a few hundred terms.
ATAN2_SLACK = 1e-13


def _light() -> FramedLight:
    """A rect light tilted off every axis (no zero component in its axes: a product's order
    shows in the bits)."""
    normal = np.array([0.2, -1.0, 0.3]) / np.linalg.norm([0.2, -1.0, 0.3])
    u, v = default_plane_axes(normal)
    hull = np.array([[-0.5, -0.3], [0.5, -0.3], [0.5, 0.3], [-0.5, 0.3]])
    return FramedLight(np.array([0.1, 2.0, -0.2]), normal, np.stack([u, v]), hull, None, None,
                       0.6, 2.0 ** -44)


def _convex(rng, width: int, grid: bool) -> tuple[np.ndarray, int]:
    """A convex counter-clockwise polygon of 3 to width corners (zero past them) about a
    random centre, its corners on sixteenths where grid."""
    k = int(rng.integers(3, width + 1))
    angle = np.sort(rng.uniform(0, 2 * np.pi, k))
    corners = np.c_[np.cos(angle), np.sin(angle)] * rng.uniform(0.2, 0.8, 2) + \
        rng.uniform(-0.3, 0.3, 2)
    if grid:
        corners = np.round(corners * 16) / 16
        corners = np.unique(corners, axis=0)
        if len(corners) < 3:
            return np.zeros((width, 2)), 0
        middle = corners.mean(axis=0)
        corners = corners[np.argsort(np.arctan2(*(corners - middle).T[::-1]))]
        k = len(corners)
    out = np.zeros((width, 2))
    out[:k] = corners
    return out, k


def _chain(rng, grid: bool) -> np.ndarray:
    """(e, 2, 2) edges: random, of no length, through the centre (a, t a), clockwise and
    counter-clockwise about it, far off (their fans clip to nothing), on sixteenths."""
    e = int(rng.integers(0, 14))
    a = rng.uniform(-0.9, 0.9, (e, 2))
    b = a + rng.normal(0, 0.4, (e, 2))
    kind = rng.integers(0, 5, e)
    b[kind == 1] = a[kind == 1]                                    # no length
    b[kind == 2] = a[kind == 2] * rng.uniform(-2, 2, ((kind == 2).sum(), 1))   # through 0
    a[kind == 3] += 5.0                                            # far off: clips to nothing
    b[kind == 3] += 5.0
    edges = np.stack([a, b], axis=1)
    if grid:
        edges = np.round(edges * 16) / 16
    return edges


def _rows(seed: int):
    """Random arguments of `_less`: (region, size, clippers, chains, owner, p, normal)."""
    rng = np.random.default_rng(seed)
    grid = seed % 2 == 0
    chains = np.empty(int(rng.integers(1, 6)), object)
    for k in range(len(chains)):
        chains[k] = _chain(rng, grid)
    n = int(rng.integers(1, 12))
    owner = rng.integers(0, len(chains), n)
    width = 6
    levels = int(rng.integers(1, 5))
    polys, counts = np.zeros((levels, n, width, 2)), np.zeros((levels, n), np.int64)
    for level in range(levels):
        for r in range(n):
            if level == 0 or rng.random() < 0.7:
                polys[level, r], counts[level, r] = _convex(rng, width, grid)
    region, size = polys[0].copy(), counts[0].copy()
    size[rng.random(n) < 0.1] = 0                                   # a region of no corners
    clippers = [(polys[level], counts[level]) for level in range(levels)]
    p = np.c_[rng.uniform(-1, 1, n), rng.uniform(-0.5, 1.0, n), rng.uniform(-1, 1, n)]
    normal = rng.normal(size=(n, 3)) + [0.0, 1.5, 0.0]
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    return region, size, clippers, chains, owner, p, normal


def _both(args, monkeypatch, arctan2=None) -> tuple[tuple, tuple]:
    """`_less` of args by the kernel and by numpy alone (the kernels' modules switched off,
    `exactkernels.inside` too; np.arctan2 replaced by `arctan2` where given)."""
    light = _light()
    fast = windmeasures._less(light, *args, False)
    with monkeypatch.context() as m:
        for name in ("measurekernels", "exactkernels"):
            m.setitem(sys.modules, f"raytrace.{name}", None)          # import fails: numpy
            assert polygons.kernels(name) is None
        if arctan2 is not None:
            m.setattr(np, "arctan2", arctan2)
        slow = windmeasures._less(light, *args, False)
    assert polygons.kernels("measurekernels") is not None
    return fast, slow


def _c_arctan2(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    """numpy's arctan2 by the C library's atan2 (Python's math.atan2 calls it, as numba's
    does)."""
    y, x = np.broadcast_arrays(y, x)
    return np.array([math.atan2(a, b) for a, b in zip(y.ravel(), x.ravel())]).reshape(y.shape)


def _check(seed: int, monkeypatch) -> None:
    args = _rows(seed)
    fast, slow = _both(args, monkeypatch, _c_arctan2)
    for a, b in zip(fast, slow):
        assert a.dtype == b.dtype == np.float64 and a.shape == b.shape == (len(args[0]),)
        assert a.tobytes() == b.tobytes(), (a - b)


@pytest.mark.parametrize("seed", range(24))
def test_random_fans_are_numpys_bytes(seed, monkeypatch):
    """Area and irradiance the same bytes as numpy's with the same atan2, on random rows."""
    _check(seed, monkeypatch)


@settings(profile(), max_examples=30 if PROFILE == "ci" else 600)
@given(seed=st.integers(24, 2 ** 32 - 1))
def test_more_random_fans_are_numpys_bytes(seed, monkeypatch):
    _check(seed, monkeypatch)


def test_the_rows_reach_every_case(monkeypatch):
    """The random rows hold what the module docstring promises: fans that clip to nothing
    and to something, edges of no length, through the centre and clockwise, clippers of no
    corners after the first, and measures that are not all zero."""
    seen = set()
    for seed in range(24):
        region, size, clippers, chains, owner, p, normal = _rows(seed)
        edges = np.concatenate(list(chains))
        signed = edges[:, 0, 0] * edges[:, 1, 1] - edges[:, 0, 1] * edges[:, 1, 0]
        seen |= {"clockwise"} if (signed < 0).any() else set()
        seen |= {"through"} if (signed == 0).any() else set()
        seen |= {"no length"} if (edges[:, 0] == edges[:, 1]).all(axis=1).any() else set()
        seen |= {"none"} if any((c[1] == 0).any() for c in clippers[1:]) else set()
        seen |= {"levels"} if len(clippers) >= 3 else set()
        fast, slow = _both((region, size, clippers, chains, owner, p, normal), monkeypatch)
        seen |= {"measured"} if (np.abs(fast[0]) > 1e-3).any() else set()
    assert seen == {"clockwise", "through", "no length", "none", "levels", "measured"}


_kernels = polygons.kernels


class _Tight:
    """`raytrace.measurekernels` whose `less` starts every row's clips in scratch of `room`
    times a convex clip's corners (0: none at all), so the rows go round its second pass."""

    def __init__(self, loaded, room: int):
        self.loaded, self.room = loaded, room

    def less(self, *args):
        return self.loaded.less(*args, self.room)

    def __getattr__(self, name: str):
        return getattr(self.loaded, name)


@pytest.mark.parametrize("room", [0, 1])
@pytest.mark.parametrize("seed", range(6))
def test_rows_with_no_room_are_measured_again_to_the_same_bytes(seed, room, monkeypatch):
    """A row whose clips find no room in `less`' scratch is measured again in more, to the
    same bytes as in room enough at once; with no room at all (0) every row is."""
    args = _rows(seed)
    light = _light()
    whole = windmeasures._less(light, *args, False)
    loaded = polygons.kernels("measurekernels")
    with monkeypatch.context() as m:
        m.setattr(polygons, "kernels", lambda name="exactkernels": _Tight(loaded, room)
                  if name == "measurekernels" else _kernels(name))
        tight = windmeasures._less(light, *args, False)
    for a, b in zip(whole, tight):
        assert a.tobytes() == b.tobytes(), (a - b)


@pytest.mark.parametrize("seed", range(8))
def test_numpys_own_arctan2_moves_only_the_irradiance_in_rounding(seed, monkeypatch):
    """With numpy's own arctan2 (SVML's under AVX-512): the areas still its bytes, the
    irradiance within ATAN2_SLACK."""
    args = _rows(seed)
    (area, irr), (want_area, want_irr) = _both(args, monkeypatch)
    assert area.tobytes() == want_area.tobytes()
    assert np.abs(irr - want_irr).max(initial=0) <= ATAN2_SLACK


# The lights over the noisy ball: a rect and a disk (numpy's alone).  (`exact_soft` measures
# a `polygon` light's pixels with GEOS, never by windings.)
LIGHTS = {
    "rect": dict(shape="rect", center=[0.0, 2.5, 0.0], normal=[0, -1, 0], size=[1.2, 1.2]),
    "disk": dict(shape="disk", center=[0.0, 2.5, 0.0], normal=[0, -1, 0], radius=0.6),
}


@pytest.mark.parametrize("kind", sorted(LIGHTS))
def test_a_noisy_balls_exact_visibility_is_the_same(kind, monkeypatch):
    """The exact soft shadow of a noisy ball on a floor (the crowded pixels measured by
    `windmeasures`): V the same bytes with and without the kernel, the irradiance within
    ATAN2_SLACK; the kernel called for the rect only."""
    pytest.importorskip("trimesh")
    from raytrace import measurekernels
    from raytrace.exact_soft import exact_visibility
    from shadowvol.scene import AreaLight
    scene = noisy_ball(AreaLight(samples=4, **LIGHTS[kind]))
    rows, plain = [], measurekernels.less

    def counted(*args):
        rows.append(len(args[0]))
        return plain(*args)
    with monkeypatch.context() as m:
        m.setattr(measurekernels, "less", counted)
        fast = exact_visibility(scene)
    assert sum(rows) >= 10 if kind != "disk" else not rows
    with monkeypatch.context() as m:
        m.setitem(sys.modules, "raytrace.measurekernels", None)
        slow = exact_visibility(scene)
    assert fast.visibility.tobytes() == slow.visibility.tobytes()
    assert np.abs(fast.irradiance - slow.irradiance).max() <= ATAN2_SLACK


def test_the_matmul_probe_names_how_numpy_rounds(monkeypatch):
    """`measurekernels.products`' modes round as they say (0: numpy's own two products and
    sum; 1 and 2: a fused multiply-add, against exact fractions), the probe's mode gives
    numpy's `a @ axes` bytes on 2,000 other points, and where no mode does, numpy measures."""
    from fractions import Fraction

    from raytrace import measurekernels
    rng = np.random.default_rng(7)
    axes = _light().axes
    a = rng.normal(size=(2000, 2)) * 10.0 ** rng.integers(-4, 4, (2000, 1))
    plain = a[:, :1] * axes[0] + a[:, 1:] * axes[1]
    assert measurekernels.products(a, axes, 0).tobytes() == plain.tobytes()
    for mode, (x, y) in ((1, (1, 0)), (2, (0, 1))):
        got = measurekernels.products(a[:50], axes, mode)
        want = [[float(Fraction(a[i, x]) * Fraction(axes[x, j])
                       + Fraction(float(a[i, y] * axes[y, j]))) for j in range(3)]
                for i in range(50)]
        assert got.tobytes() == np.array(want).tobytes()
    mode = windmeasures._matmul_mode(measurekernels, axes)
    assert mode is not None
    assert measurekernels.products(a, axes, mode).tobytes() == (a @ axes).tobytes()

    class Unlike:
        def products(self, a, axes, mode):
            return np.nextafter(a @ axes, np.inf)
    assert windmeasures._matmul_mode(Unlike(), axes) is None
    args = _rows(3)
    want = _both(args, monkeypatch)[1]
    with monkeypatch.context() as m:
        m.setattr(windmeasures, "_matmul_mode", lambda loaded, axes: None)
        m.setattr(measurekernels, "less", None)                       # never called
        got = windmeasures._less(_light(), *args, False)
    assert all(g.tobytes() == w.tobytes() for g, w in zip(got, want))
