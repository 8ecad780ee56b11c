"""The measures of `raytrace.polygons` against independent float64 integrals (scipy's adaptive
quadrature of cos / r^2 over the light): a polygon's Lambert irradiance at a tilted receiver, a
disk's whole and a disk cut by a line (its arcs in closed form), and their areas.

Tolerance: QUAD_TOL, the absolute error asked of scipy (its estimate stays below it on these
smooth integrands: the receiver is 0.3 or more from the light), plus float64 rounding of the
closed forms (~1e-15).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from raytrace.polygons import _Arcs, disk_ring_measures, ring_measures

QUAD_TOL = 1e-10
AXES = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])   # u, v; u x v = (0, -1, 0): emits down
CENTER = np.array([0.2, 2.0, -0.3])


def _cosine_integral(eye, normal, x_lo, x_hi, z_lo, z_hi):
    """∫∫ cos_r cos_e / r² over the part of the light's plane (y = CENTER.y) with u in
    [x_lo, x_hi] and v in [z_lo(u), z_hi(u)] (u, v about CENTER), unit radiance."""
    def f(v, u):
        x = CENTER + u * AXES[0] + v * AXES[1] - eye
        r2 = x @ x
        return (normal @ x) * x[1] / r2 ** 2   # cos at the light (its normal -y): x.y / r
    value, error = integrate.dblquad(f, x_lo, x_hi, z_lo, z_hi, epsabs=QUAD_TOL / 10,
                                     epsrel=1e-13)
    assert error < QUAD_TOL
    return value


def _random_view(rng):
    """A receiver point below the light and a unit normal that sees the whole light (every
    corner of the light's 2 x 2 box above its tangent plane)."""
    while True:
        eye = np.array([rng.uniform(-1, 1), rng.uniform(0.0, 1.7), rng.uniform(-1, 1)])
        normal = rng.normal(size=3) + np.array([0.0, 2.0, 0.0])
        normal /= np.linalg.norm(normal)
        box = CENTER + np.array([[a, 0, b] for a in (-1, 1) for b in (-1, 1)], float)
        if ((box - eye) @ normal > 0.05).all():
            return eye, normal


@pytest.mark.parametrize("seed", range(4))
def test_polygon_lambert_against_quadrature(seed):
    rng = np.random.default_rng(seed)
    eye, normal = _random_view(rng)
    # a convex quadrilateral inside the 2 x 2 box (corners on an ellipse), counter-clockwise,
    # and reversed
    angles = np.sort(rng.uniform(0, 2 * np.pi, 4))
    ring = np.stack([np.cos(angles), np.sin(angles)], 1) * rng.uniform(0.4, 0.95, 2)
    closed = np.vstack([ring, ring[:1]])
    for coords in (closed, closed[::-1]):
        area, irr = ring_measures(coords, np.zeros(5, int), 1, eye[None], normal[None],
                                  CENTER, AXES)
        # the quadrilateral as u-slices: between its lower and upper outline at each u
        lo, hi = _slices(ring)
        want = _cosine_integral(eye, normal, ring[:, 0].min(), ring[:, 0].max(), lo, hi)
        assert irr[0] == pytest.approx(want, abs=QUAD_TOL)
        nxt = np.roll(ring, -1, 0)
        shoelace = 0.5 * abs((ring[:, 0] * nxt[:, 1] - ring[:, 1] * nxt[:, 0]).sum())
        assert area[0] == pytest.approx(shoelace, rel=1e-14)


def _slices(ring):
    """(lower(u), upper(u)) of a convex polygon (m, 2)."""
    def bounds(u):
        hits = []
        m = len(ring)
        for i in range(m):
            (a0, b0), (a1, b1) = ring[i], ring[(i + 1) % m]
            if min(a0, a1) <= u <= max(a0, a1) and a0 != a1:
                hits.append(b0 + (u - a0) / (a1 - a0) * (b1 - b0))
        return min(hits), max(hits)
    return (lambda u: bounds(u)[0]), (lambda u: bounds(u)[1])


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("cut", [None, -0.45, 0.3])
def test_disk_against_quadrature(seed, cut):
    """The disk of radius R inside a square ring (the whole disk) or inside the square cut at
    u = cut (the disk less a segment: an arc and a chord)."""
    rng = np.random.default_rng(10 + seed)
    eye, normal = _random_view(rng)
    radius = 0.8
    right = 1.0 if cut is None else cut
    square = np.array([[-1, -1], [right, -1], [right, 1], [-1, 1], [-1, -1]], float)
    area, irr = disk_ring_measures(square, np.zeros(5, int), 1, radius, eye[None],
                                   normal[None], CENTER, AXES)
    top = min(right, radius)
    want = _cosine_integral(eye, normal, -radius, top,
                            lambda u: -math.sqrt(max(radius * radius - u * u, 0.0)),
                            lambda u: math.sqrt(max(radius * radius - u * u, 0.0)))
    assert irr[0] == pytest.approx(want, abs=QUAD_TOL)
    # the area of the disk left of u = top: R² (θ - sin θ cos θ) form of the circular segment
    theta = math.acos(top / radius)
    segment = radius * radius * (theta - math.sin(theta) * math.cos(theta))
    assert area[0] == pytest.approx(math.pi * radius ** 2 - segment, rel=1e-13)


def test_arc_integral_is_continuous_past_pi_and_exact_on_axis():
    """The closed-form arc term over a full turn from several starts (its atan branches) and on
    the axis (rho = 0, the limits of atan(x)/x and log1p(x)/x): on-axis the whole circle gives
    π R² / (R² + d²), the disk's irradiance at distance d below its centre."""
    radius, d = 0.7, 1.3
    c = np.array([[0.0, d, 0.0]])          # the centre seen from the receiver, 1.3 above it
    normal = np.array([[0.0, 1.0, 0.0]])
    arcs = _Arcs(radius, c, normal, AXES)
    full = [abs(arcs.integral(np.array([s]), np.array([2 * np.pi]))[0])
            for s in (-3.0, -1.0, 0.5, 3.1)]
    assert full == pytest.approx([math.pi * radius ** 2 / (radius ** 2 + d ** 2)] * 4,
                                 rel=1e-14)
    halves = sum(arcs.integral(np.array([s]), np.array([np.pi]))[0] for s in (2.0, 2.0 + np.pi))
    assert abs(halves) == pytest.approx(full[0], rel=1e-14)
