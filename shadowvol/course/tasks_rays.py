"""The ray tasks' hidden cases, their answers computed by the ray tracer itself
(`raytrace.intersect`, `raytrace.outlook.whitted`): ray-plane, ray-sphere, ray-triangle, (the
light's tasks are `tasks_light`'s).

Every case list is built from fixed numbers and a seeded generator, the same on every run.
"""

from __future__ import annotations

import math

import numpy as np

from raytrace.intersect import hesse, plane_coordinates, ray_plane, ray_sphere, ray_triangle
from shadowvol.course.task import (
    Case,
    Task,
    is_number,
    judge_lambda,
    judge_vector,
    num,
    vec,
)


def _floats(v) -> list:
    return [float(x) for x in np.asarray(v, float).reshape(-1)]


def _lam(value) -> float | None:
    value = float(value)
    return value if math.isfinite(value) else None


def _unit(v) -> np.ndarray:
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


# ---------------------------------------------------------------------------------------------
# Ray against plane
# ---------------------------------------------------------------------------------------------

def plane_cases() -> list[Case]:
    fixed = [
        ("the lecture's exercise", (5, 1), (-1, 3), (2, 2), (1, -1)),
        ("the plane behind the ray (λ < 0)", (5, 1), (1, -3), (2, 2), (1, -1)),
        ("the origin on the plane (λ = 0: no hit)", (3, 3), (1, 2), (2, 2), (1, -1)),
        ("a ray parallel to the plane", (5, 1), (1, 1), (2, 2), (1, -1)),
        ("a ray inside the plane (parallel)", (3, 3), (2, 2), (2, 2), (1, -1)),
        ("a nearly grazing ray", (0, 0, 1), (1, 0, -0.001), (0, 0, 0), (0, 0, 1)),
        ("a normal that is not unit length", (0, 0, 5), (0.5, 0.2, -1), (1, 1, 1), (0, 0, 7)),
        ("the normal facing away from the ray", (0, 0, 5), (0, 0, -2), (0, 0, 1), (0, 0, -1)),
    ]
    rng = np.random.default_rng(1)
    while len(fixed) < 16:
        o, r, a, n = (rng.uniform(-4, 4, 3) for _ in range(4))
        if abs(_unit(n) @ _unit(r)) > 0.2:
            fixed.append(("a ray in 3D", *(np.round(v, 3) for v in (o, r, a, n))))
    out = []
    for label, o, r, a, n in fixed:
        unit, d = hesse(a, n)
        lam = ray_plane(np.asarray(o, float)[None], np.asarray(r, float)[None], unit, d)[0]
        out.append(Case(label, tuple(_floats(v) for v in (o, r, a, n)), _lam(lam)))
    return out


def _show_plane(args) -> str:
    o, r, a, n = args
    return f"ray {vec(o)} + λ {vec(r)}, plane through {vec(a)} with normal {vec(n)}"


# ---------------------------------------------------------------------------------------------
# Ray against sphere
# ---------------------------------------------------------------------------------------------

def sphere_cases() -> list[Case]:
    fixed = [
        ("a ray from outside, head-on", (0, 0, -5), (0, 0, 1), (0, 0, 0), 1.0),
        ("a ray starting inside the sphere", (0, 0, 0.5), (0, 0, 1), (0, 0, 0), 1.0),
        ("the sphere behind the ray", (0, 0, 5), (0, 0, 1), (0, 0, 0), 1.0),
        ("a grazing ray (tangent)", (-5, 1, 0), (1, 0, 0), (0, 0, 0), 1.0),
        ("a ray passing just outside", (-5, 1.5, 0), (1, 0, 0), (0, 0, 0), 1.0),
        ("the origin on the sphere, leaving it", (1, 0, 0), (1, 0, 0), (0, 0, 0), 1.0),
        ("the origin on the sphere, entering it", (1, 0, 0), (-1, 0, 0), (0, 0, 0), 1.0),
        ("a circle in 2D", (4, 3), (-2, -1), (1, 1), 1.5),
        ("a direction that is not unit length", (0, -6, 0), (0, 4, 0), (0, 0, 0), 2.0),
        ("inside the sphere, a direction not unit length", (0, 0, 0.5), (0, 0, 3), (0, 0, 0),
         1.0),
    ]
    rng = np.random.default_rng(2)
    while len(fixed) < 16:
        o, c = rng.uniform(-4, 4, 3), rng.uniform(-2, 2, 3)
        radius = float(np.round(rng.uniform(0.5, 2.5), 3))
        r = np.round(c - o + rng.normal(0, 1, 3), 3)
        if abs(np.linalg.norm(o - c) - radius) > 0.5:
            fixed.append(("a ray in 3D", np.round(o, 3), r, np.round(c, 3), radius))
    out = []
    for label, o, r, c, radius in fixed:
        lam = ray_sphere(np.asarray(o, float)[None], np.asarray(r, float)[None], c, radius)[0]
        out.append(Case(label, (_floats(o), _floats(r), _floats(c), float(radius)), _lam(lam)))
    return out


def _show_sphere(args) -> str:
    o, r, c, radius = args
    return f"ray {vec(o)} + λ {vec(r)}, sphere centre {vec(c)} radius {num(radius)}"


# ---------------------------------------------------------------------------------------------
# Ray against triangle
# ---------------------------------------------------------------------------------------------

TRIANGLE = ((0, 0, 0), (2, 0, 0), (0, 2, 0))


def triangle_cases() -> list[Case]:
    down = (0, 0, -1)
    fixed = [
        ("a hit inside", (0.5, 0.25, 3), down, *TRIANGLE),
        ("a hit exactly on the edge b-c (β + γ = 1)", (1, 1, 5), down, *TRIANGLE),
        ("a hit exactly at the corner a", (0, 0, 2), down, *TRIANGLE),
        ("a hit exactly on the edge a-b (γ = 0)", (1.5, 0, 1), (0, 0, -0.5), *TRIANGLE),
        ("a miss beside the edge a-b (γ < 0)", (1, -0.5, 2), down, *TRIANGLE),
        ("a miss past the edge b-c (β + γ > 1)", (1.5, 1.5, 2), down, *TRIANGLE),
        ("a miss beside the edge a-c (β < 0)", (-0.25, 1, 2), down, *TRIANGLE),
        ("the triangle behind the ray", (0.5, 0.5, -2), down, *TRIANGLE),
        ("the origin on the triangle (λ = 0: no hit)", (0.5, 0.5, 0), down, *TRIANGLE),
        ("a hit before the direction's length (λ < 1)", (0.5, 0.5, 1), (0, 0, -4), *TRIANGLE),
        ("a ray parallel to the triangle", (0.5, 0.5, 1), (1, 0, 0), *TRIANGLE),
        ("a hit on the back of the triangle", (0.5, 0.5, -2), (0, 0, 1), *TRIANGLE),
    ]
    rng = np.random.default_rng(3)
    while len(fixed) < 18:
        a, b, c = (np.round(rng.uniform(-2, 2, 3), 3) for _ in range(3))
        target = a + rng.uniform(-0.3, 1.0) * (b - a) + rng.uniform(-0.3, 1.0) * (c - a)
        o = np.round(rng.uniform(-4, 4, 3), 3)
        r = np.round(target - o, 3)
        normal = _unit(np.cross(b - a, c - a))
        if abs(normal @ _unit(r)) > 0.2:
            fixed.append(("a ray in 3D", o, r, a, b, c))
    return [Case(label, tuple(_floats(v) for v in (o, r, a, b, c)), _triangle(o, r, a, b, c))
            for label, o, r, a, b, c in fixed]


def _triangle(o, r, a, b, c):
    """(λ, β, γ) of the witness, or None."""
    o, r, a, b, c = (np.asarray(v, float) for v in (o, r, a, b, c))
    lam = float(ray_triangle(o, r, a, b, c))
    if not math.isfinite(lam):
        return None
    beta, gamma = plane_coordinates(o + lam * r, a, b - a, c - a)
    return [lam, float(beta), float(gamma)]


def _judge_triangle(expected, got) -> str | None:
    if expected is None:
        return None if got is None else \
            f"expected no hit (None), got {_show_triangle_answer(got)}"
    if got is None:
        return f"expected a hit at λ = {num(expected[0])}, got None (a miss)"
    return judge_vector(expected, got, "(λ, β, γ)")


def _show_triangle(args) -> str:
    o, r, a, b, c = args
    return f"ray {vec(o)} + λ {vec(r)}, triangle a = {vec(a)}, b = {vec(b)}, c = {vec(c)}"


def _show_triangle_answer(v) -> str:
    if v is None:
        return "no hit (None)"
    if isinstance(v, list) and len(v) == 3 and all(is_number(x) for x in v):
        lam, beta, gamma = v
        return f"λ = {num(lam)}, β = {num(beta)}, γ = {num(gamma)}"
    return vec(v) if isinstance(v, list) else num(v)


TASKS = [
    Task("ray_plane", "intersect", "ray against plane", 10, plane_cases, judge_lambda,
         _show_plane, lambda v: "no hit (None)" if v is None else f"λ = {num(v)}", False),
    Task("ray_sphere", "intersect", "ray against sphere", 10, sphere_cases, judge_lambda,
         _show_sphere, lambda v: "no hit (None)" if v is None else f"λ = {num(v)}", False),
    Task("ray_triangle", "intersect", "ray against triangle", 10, triangle_cases,
         _judge_triangle, _show_triangle, _show_triangle_answer),
]
