"""The course's intersection formulas, checked against cases worked out by hand: hits, misses,
grazing rays and hits behind the origin for planes, spheres and triangles; Snell's law and total
internal reflection; primary rays of the camera."""

import math

import numpy as np
import pytest

from raytrace.camera import camera_basis, primary_rays
from raytrace.intersect import (
    hesse,
    ray_parallelogram,
    ray_plane,
    ray_sphere,
    ray_triangle,
    reflect,
    refract,
)
from shadowvol.scene import Camera

INF = np.inf


def rays(*pairs):
    o = np.array([p[0] for p in pairs], dtype=float)
    d = np.array([p[1] for p in pairs], dtype=float)
    return o, d


# --- planes (Hesse normal form) ----------------------------------------------------------------

def test_course_exercise_2d():
    """The ray (5,1) + λ(−1,3) meets the plane (a line in 2D) through (2,2) with normal (1,−1)
    at λ = 1, in the point (4,4)."""
    n, dist = hesse([2, 2], [1, -1])
    assert np.allclose(n, np.array([1, -1]) / math.sqrt(2)) and dist == pytest.approx(0.0)
    o, d = rays(([5, 1], [-1, 3]))
    lam = ray_plane(o, d, n, dist)
    assert lam[0] == pytest.approx(1.0)
    assert np.allclose(o[0] + lam[0] * d[0], [4, 4])


def test_plane_hit_miss_parallel_behind():
    n, dist = hesse([0, 2, 0], [0, 1, 0])  # the plane y = 2
    o, d = rays(([0, 0, 0], [0, 1, 0]),      # straight up: hits at 2
                ([1, 0, 3], [0, 2, 0]),      # unnormalised direction: λ in units of |d|
                ([0, 0, 0], [1, 0, 0]),      # parallel, below: never meets it
                ([0, 2, 0], [1, 0, 0]),      # grazing: inside the plane -> a miss by convention
                ([0, 5, 0], [0, 1, 0]),      # the plane is behind the origin
                ([0, 2, 0], [0, 1, 0]))      # starts on it: λ = 0 is not > 0
    assert np.array_equal(ray_plane(o, d, n, dist), [2.0, 1.0, INF, INF, INF, INF])


# --- spheres -----------------------------------------------------------------------------------

def test_sphere_cases():
    c, r = np.array([0.0, 0.0, -5.0]), 1.0
    o, d = rays(([0, 0, 0], [0, 0, -1]),       # head on: near side at 4
                ([0, 0, -5], [1, 0, 0]),       # from the centre: the far root, R
                ([0, 1, 0], [0, 0, -1]),       # tangent (Δ = 0), grazing: touches at 5
                ([0, 1.001, 0], [0, 0, -1]),   # just above: miss
                ([0, 0, 0], [0, 0, 1]),        # sphere behind the origin
                ([0, 0, -7], [0, 0, 1]),       # from behind, toward it: 1
                ([0, 0, 0], [0, 0, -2]))       # unnormalised: λ = 4 / 2
    lam = ray_sphere(o, d, c, r)
    assert lam == pytest.approx([4.0, 1.0, 5.0, INF, INF, 1.0, 2.0])


def test_circle_2d():
    """The same quadratic in 2D: a circle of radius 2 at (3, 0), rays from the origin."""
    o, d = rays(([0, 0], [1, 0]), ([0, 0], [0, 1]), ([0, 2], [1, 0]))
    assert ray_sphere(o, d, [3.0, 0.0], 2.0) == pytest.approx([1.0, INF, 3.0])


def test_sphere_root_is_accurate_for_a_ray_leaving_the_surface():
    """A ray starting a hair outside and going away must miss (no cancellation in the root)."""
    c, r = np.zeros(3), 1e3
    o, d = rays(([0, 0, r * (1 + 1e-12)], [0.6, 0, 0.8]), ([0, 0, r * (1 - 1e-12)], [0, 0, -1]))
    lam = ray_sphere(o, d, c, r)
    assert lam[0] == INF
    assert lam[1] == pytest.approx(2 * r)


# --- triangles and parallelograms --------------------------------------------------------------

A, B, C = np.array([0.0, 0, 0]), np.array([4.0, 0, 0]), np.array([0.0, 4, 0])


def test_triangle_cases():
    o, d = rays(([1, 1, 3], [0, 0, -1]),        # inside: hits at 3
                ([3, 3, 3], [0, 0, -1]),        # beyond the hypotenuse: miss
                ([2, 2, 3], [0, 0, -1]),        # on the hypotenuse: edges count
                ([0, 0, 3], [0, 0, -1]),        # on a corner
                ([-0.001, 1, 3], [0, 0, -1]),   # just outside an edge
                ([1, 1, 3], [0, 0, 1]),         # triangle behind the origin
                ([1, 1, 0], [1, 0, 0]),         # grazing: in its plane -> miss
                ([1, 1, -2], [0, 0, 1]))        # from the back side: surfaces are two-sided
    lam = ray_triangle(o, d, A, B, C)
    assert lam == pytest.approx([3.0, INF, 3.0, 3.0, INF, INF, INF, 2.0])


def test_triangle_barycentric_point_and_broadcasting():
    """(n, 1, 3) rays against (1, m, 3) triangles give (n, m); the hit point is the
    barycentric combination α a + β b + γ c."""
    rng = np.random.default_rng(7)
    tri = rng.normal(size=(5, 3, 3))
    bary = rng.dirichlet([1, 1, 1], size=5)
    targets = np.einsum("mk,mkj->mj", bary, tri)
    o = targets + rng.normal(size=(5, 3)) * 3
    d = targets - o
    lam = ray_triangle(o[:, None], d[:, None], tri[None, :, 0], tri[None, :, 1], tri[None, :, 2])
    assert lam.shape == (5, 5)
    assert np.diag(lam) == pytest.approx(np.ones(5))


def test_degenerate_triangle_is_missed():
    o, d = rays(([1, 0, 1], [0, 0, -1]), ([1, 0, 0], [1, 0, 0]))
    assert np.all(ray_triangle(o, d, A, B, 2 * B) == INF)


def test_parallelogram():
    corner, eu, ev = np.array([0.0, 0, 0]), np.array([2.0, 0, 0]), np.array([1.0, 0, 1])
    o, d = rays(([1.5, 1, 0.5], [0, -1, 0]),    # inside (s = 0.5, t = 0.5)
                ([2.9, 1, 0.95], [0, -1, 0]),   # near the far corner, inside
                ([0.1, 1, 0.9], [0, -1, 0]),    # left of the slanted edge: outside
                ([1.5, -1, 0.5], [0, -1, 0]))   # behind
    assert ray_parallelogram(o, d, corner, eu, ev) == pytest.approx([1.0, 1.0, INF, INF])


# --- reflection and refraction -----------------------------------------------------------------

def test_reflect():
    d = np.array([[1.0, -1.0, 0.0]]) / math.sqrt(2)
    assert np.allclose(reflect(d, np.array([[0.0, 1, 0]])), [[1, 1, 0] / np.sqrt(2)])


def test_snell_air_to_glass_and_back():
    theta1 = math.radians(30)
    d = np.array([[math.sin(theta1), -math.cos(theta1), 0.0]])
    n = np.array([[0.0, 1.0, 0.0]])
    t, tir = refract(d, n, 1 / 1.5)
    assert not tir[0]
    assert np.linalg.norm(t[0]) == pytest.approx(1.0)
    assert t[0, 0] == pytest.approx(math.sin(theta1) / 1.5)  # n1 sin θ1 = n2 sin θ2
    assert t[0, 1] < 0  # it went through
    back, tir = refract(-t, -n, 1.5)  # reversibility of light paths
    assert not tir[0] and np.allclose(back, -d)


def test_total_internal_reflection():
    critical = math.asin(1 / 1.5)
    n = np.array([[0.0, -1.0, 0.0], [0.0, -1.0, 0.0]])  # inside glass, facing the ray
    angles = [critical + 1e-6, critical - 1e-6]
    d = np.array([[math.sin(a), math.cos(a), 0.0] for a in angles])
    t, tir = refract(d, n, np.array([1.5, 1.5]))
    assert tir.tolist() == [True, False]
    assert np.allclose(t[0], reflect(d[:1], n[:1])[0])  # all of it reflected
    assert t[1, 1] > 0 and abs(t[1, 0]) == pytest.approx(1.0, abs=2e-3)  # grazing exit


# --- camera ------------------------------------------------------------------------------------

def test_primary_rays_follow_the_conventions():
    cam = Camera(eye=[1.0, 2.0, 3.0], target=[1.0, 2.0, -7.0], fov_y=90.0, near=0.5)
    W, H = 4, 2
    o, d = primary_rays(cam, W, H)
    right, up, back = camera_basis(cam)
    assert np.allclose([right, up, back], np.eye(3))
    # Pixel (0, 0), top left: NDC (-0.75, 0.5); tan(45°) = 1, aspect 2 -> eye dir (-1.5, 0.5, -1).
    expect = np.array([-1.5, 0.5, -1.0])
    assert np.allclose(d[0], expect / np.linalg.norm(expect))
    assert np.allclose(o[0], cam.eye + 0.5 * expect)  # starts on the near plane
    # Every ray starts at eye-space depth == near: a plane, not a sphere.
    assert np.allclose((o - cam.eye) @ -back, 0.5)
    # Row 0 is the top: the last row's rays point down.
    assert np.all(d[:W, 1] > 0) and np.all(d[-W:, 1] < 0)
    o32, d32 = primary_rays(cam, W, H, rows=slice(1, 2), dtype=np.float32, unit=False)
    assert o32.dtype == np.float32 and np.allclose(o32, o[W:])
    assert np.allclose(d32 @ -back, 1.0)  # depth-1 directions
