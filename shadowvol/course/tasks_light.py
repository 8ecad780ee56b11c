"""The light's tasks' hidden cases, their answers computed by the ray tracer itself
(`raytrace.intersect`, `raytrace.outlook.whitted`): the ideal reflection, Snell's refraction with total
internal reflection, the shadow-ray test and Phong at a point.

Every case list is built from fixed numbers and a seeded generator, the same on every run.
"""

from __future__ import annotations

import numpy as np

from raytrace.intersect import ray_sphere, reflect, refract
from raytrace.outlook.whitted import World, local_colour
from shadowvol.course.task import Case, Task, judge_exact, judge_vector, num, show_value, vec
from shadowvol.primitives import sphere
from shadowvol.scene import Camera, Material, PointLight, Scene

# The shadow ray's start above the surface, along the normal.  The cases' points lie 1e-12
# inside their sphere (as a computed hit point may), and every case is kept only when offsets
# of 1e-9 and 1e-4 give the same answer as this one: any offset in that range passes.
SHADOW_OFFSET = 1e-6
SHADOW_OFFSETS_ACCEPTED = (1e-9, 1e-4)
# How far inside its sphere a case's surface point lies: a rounding error's worth, large
# enough that a shadow ray started on it without an offset meets its own sphere.
INSIDE = 1e-12


def _floats(v) -> list:
    return [float(x) for x in np.asarray(v, float).reshape(-1)]


def _unit(v) -> np.ndarray:
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


# ---------------------------------------------------------------------------------------------
# Reflection
# ---------------------------------------------------------------------------------------------

def reflection_cases() -> list[Case]:
    fixed = [
        ("45 degrees in 2D", (1, -1), (0, 2)),
        ("head-on", (0, 0, -3), (0, 0, 1)),
        ("a grazing direction (along the surface)", (2, 0, 0), (0, 0, 1)),
        ("the normal on the far side", (1, -1, 0), (0, -1, 0)),
        ("a normal that is not unit length", (0.3, -2, 0.5), (0.1, 4, -0.2)),
    ]
    rng = np.random.default_rng(4)
    for _ in range(7):
        fixed.append(("a direction in 3D", np.round(rng.uniform(-3, 3, 3), 3),
                      np.round(rng.uniform(-3, 3, 3), 3)))
    out = []
    for label, d, n in fixed:
        d, n = np.asarray(d, float), np.asarray(n, float)
        out.append(Case(label, (_floats(d), _floats(n)), _floats(reflect(d, _unit(n)))))
    return out


def _show_reflection(args) -> str:
    return f"direction d = {vec(args[0])}, normal n = {vec(args[1])}"


# ---------------------------------------------------------------------------------------------
# Refraction
# ---------------------------------------------------------------------------------------------

def _incoming(sin1: float, tangent, normal) -> np.ndarray:
    """The unit direction meeting a surface of unit normal `normal` at sin θ1 = sin1."""
    return sin1 * _unit(tangent) - np.sqrt(1.0 - sin1 * sin1) * _unit(normal)


def refraction_cases() -> list[Case]:
    up, x = (0.0, 1.0, 0.0), (1.0, 0.0, 0.0)
    sin_past, sin_before = (np.sqrt((1.0 - k) / 1.5 ** 2) for k in (-1e-6, 1e-6))
    fixed = [
        ("head-on, air into glass", 0.0, 1.0, 1.5, x, up),
        ("30 degrees, air into glass", 0.5, 1.0, 1.5, x, up),
        ("20 degrees, glass into air", np.sin(np.radians(20)), 1.5, 1.0, x, up),
        ("60 degrees, glass into air: past the critical angle", np.sin(np.radians(60)), 1.5,
         1.0, x, up),
        ("a hair below the critical angle (refracted, almost grazing)", sin_before, 1.5, 1.0,
         x, up),
        ("a hair past the critical angle (total internal reflection)", sin_past, 1.5, 1.0, x,
         up),
        ("water into glass", 0.6, 1.33, 1.5, (0, 0, 1), (0, 0.6, 0.8)),
    ]
    rng = np.random.default_rng(5)
    for n1, n2 in ((1.0, 1.5), (1.5, 1.0), (1.0, 2.4), (2.4, 1.0), (1.5, 1.33), (1.2, 1.0)):
        n = _unit(rng.normal(size=3))
        t = np.cross(n, rng.normal(size=3))
        fixed.append((f"in 3D, n1 = {n1}, n2 = {n2}", float(rng.uniform(0.05, 0.95)), n1, n2,
                      t, n))
    out = []
    for label, sin1, n1, n2, t, n in fixed:
        d, n = _incoming(sin1, t, n), _unit(n)
        out.append(Case(label, (_floats(d), _floats(n), n1, n2), _refracted(d, n, n1, n2)))
    # Exactly at the critical angle k = 0, and float64 cannot tell its sign (k is about
    # ±4e-16 here, by formula): the grazing refraction and the total reflection are both right.
    d, n = np.array([0.5, -np.sqrt(0.75), 0.0]), np.array([0.0, 1.0, 0.0])
    grazing = [_floats(2.0 * d + 2.0 * np.sqrt(0.75) * n), False]
    mirror = [_floats(reflect(d, n)), True]
    expected = _refracted(d, n, 2.0, 1.0)
    out.append(Case("exactly at the critical angle (glass of index 2 into air, 30 degrees)",
                    (_floats(d), _floats(n), 2.0, 1.0), expected,
                    (grazing if expected[1] else mirror,)))
    return out


def _refracted(d, n, n1, n2) -> list:
    t, tir = refract(np.asarray(d, float)[None], np.asarray(n, float)[None], n1 / n2)
    return [_floats(t[0]), bool(tir[0])]


def _judge_refraction(expected, got) -> str | None:
    if not isinstance(got, list) or len(got) != 2:
        return f"expected a pair (t, tir), got {show_value(got)}"
    if got[1] is not expected[1]:
        return "total internal reflection expected" if expected[1] else \
            "no total internal reflection here, but tir is " + show_value(got[1])
    return judge_vector(expected[0], got[0], "t")


def _show_refraction(args) -> str:
    d, n, n1, n2 = args
    return f"direction d = {vec(d)}, normal n = {vec(n)}, n1 = {num(n1)}, n2 = {num(n2)}"


def _show_refracted(v) -> str:
    if isinstance(v, list) and len(v) == 2:
        return f"t = {show_value(v[0])}, tir = {show_value(v[1])}"
    return show_value(v)


# ---------------------------------------------------------------------------------------------
# The shadow ray
# ---------------------------------------------------------------------------------------------

def _blocked(p, n, light, spheres, offset: float = SHADOW_OFFSET) -> bool:
    """The witness: the segment from p + offset·n to the light against every sphere."""
    start = np.asarray(p, float) + offset * np.asarray(n, float)
    direction = np.asarray(light, float) - start
    return any(float(ray_sphere(start[None], direction[None], c, r)[0]) < 1.0
               for c, r in spheres)


def _on_sphere(center, radius, normal):
    """A point of the sphere where its unit normal is `normal`, INSIDE below its surface."""
    n = _unit(normal)
    return np.asarray(center, float) + (radius - INSIDE) * n, n


def shadow_cases() -> list[Case]:
    own = ((0.0, 0.0, 0.0), 1.0)
    top = _on_sphere(*own, (0, 1, 0))
    fixed = [
        ("a sphere between the point and the light", *top, (0, 5, 0), [own, ((0, 3, 0), 0.5)]),
        ("a sphere beyond the light", *top, (0, 2, 0), [own, ((0, 3, 0), 0.5)]),
        ("a sphere behind the point", *top, (0, 5, 0), [own, ((0, -3, 0), 0.5)]),
        ("the ray starts on its own sphere, nothing else in the way", *top, (1, 4, 2), [own]),
        ("the surface faces away from the light", *top, (0, -5, 0), [own]),
        ("the light exactly at the horizon", *top, (5, 1, 0), [own]),
        ("a ray passing just beside a small sphere", *top, (0, 5, 0), [own, ((0.8, 3, 0), 0.5)]),
        ("the light inside a sphere", *top, (0, 3, 0), [own, ((0, 3, 0), 0.5)]),
        ("the point inside another sphere", *top, (0, 5, 0), [own, ((0, 1.2, 0), 0.5)]),
    ]
    rng = np.random.default_rng(6)
    while len(fixed) < 21:
        p, n = _on_sphere(*own, rng.normal(size=3))
        light = np.round(rng.normal(size=3) * 4, 3)
        spheres = [own] + [(tuple(np.round(rng.uniform(-3, 3, 3), 3)),
                            float(np.round(rng.uniform(0.3, 1.0), 3))) for _ in range(2)]
        if np.linalg.norm(light) < 2 or any(np.linalg.norm(light - np.asarray(c)) < r + 0.1
                                            for c, r in spheres):
            continue
        fixed.append(("a point on a sphere among two others", p, n, light, spheres))
    out = []
    for label, p, n, light, spheres in fixed:
        answer = _blocked(p, n, light, spheres)
        grown = [(c, r + 1e-3) for c, r in spheres[1:]]
        shrunk = [(c, r - 1e-3) for c, r in spheres[1:]]
        stable = {_blocked(p, n, light, spheres, e) for e in SHADOW_OFFSETS_ACCEPTED} | \
            {_blocked(p, n, light, spheres[:1] + s) for s in (grown, shrunk)}
        if stable != {answer}:
            continue   # the answer would hang on the offset or on a hair: not a fair case
        out.append(Case(label, (_floats(p), _floats(n), _floats(light),
                                [[_floats(c), float(r)] for c, r in spheres]), answer))
    return out


def _show_shadow(args) -> str:
    p, n, light, spheres = args
    listed = ", ".join(f"(centre {vec(c)}, radius {num(r)})" for c, r in spheres)
    return f"point p = {vec(p)}, normal n = {vec(n)}, light L = {vec(light)}, spheres {listed}"


# ---------------------------------------------------------------------------------------------
# Phong
# ---------------------------------------------------------------------------------------------

def _phong(p, n, eye, light, colour, ambient, ka, kd, ks, shininess) -> list:
    """The ray tracer's local term at p: a sphere of radius 1 touching p with normal n there,
    one point light, the Whitted shading (`raytrace.outlook.whitted.local_colour`)."""
    p, n, eye = (np.asarray(v, float) for v in (p, n, eye))
    material = Material(ambient=ka, diffuse=kd, specular=ks, shininess=shininess)
    scene = Scene(camera=Camera(eye=eye, target=p, fov_y=30.0),
                  objects=[sphere("surface", p - n, 1.0, material)],
                  lights=[PointLight(position=light, color=colour)], ambient=ambient,
                  width=1, height=1)
    view = _unit(eye - p)
    return _floats(local_colour(World(scene, backend="numpy"), scene, p[None], n[None],
                                view[None], np.array([0]))[0])


def phong_cases() -> list[Case]:
    grey, white = (0.1, 0.1, 0.1), (1.0, 1.0, 1.0)
    up, origin = (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)
    material = ((0.2, 0.2, 0.2), (0.6, 0.5, 0.4), (0.3, 0.3, 0.3), 8.0)
    fixed = [   # (label, point, normal, eye, light, light colour, ambient, ka, kd, ks, s)
        ("light and eye straight above", origin, up, (0, 0, 3), (0, 0, 5), white, grey,
         *material),
        ("the highlight away from the eye (r·v < 0)", origin, up, (4, 0, 3), (4, 0, 3), white,
         grey, *material),
        ("the light below the surface, the eye grazing", origin, up, (-10, 0, 1), (3, 0, -4),
         white, grey, *material),
        ("the light exactly at the horizon", origin, up, (-2, 1, 2), (3, 0, 0), white, grey,
         *material),
        ("the eye in the mirror direction", origin, up, (3, 0, 3), (-2, 0, 2), white, grey,
         *material),
    ]
    rng = np.random.default_rng(7)
    while len(fixed) < 14:
        n = _unit(rng.normal(size=3))
        p = np.round(rng.uniform(-1, 1, 3), 3)
        eye, light = p + 4 * _unit(n + rng.normal(size=3) * 0.6), p + np.round(
            rng.normal(size=3) * 3, 3)
        colours = [tuple(np.round(rng.uniform(0, 1, 3), 3)) for _ in range(5)]
        fixed.append(("a coloured light in 3D", p, n, eye, light, *colours,
                      float(rng.choice([4, 16, 50]))))
    out = []
    for label, p, n, eye, light, colour, ambient, ka, kd, ks, s in fixed:
        args = (_floats(p), _floats(_unit(n)), _floats(eye), _floats(light), _floats(colour),
                _floats(ambient), _floats(ka), _floats(kd), _floats(ks), float(s))
        out.append(Case(label, args, _phong(*args)))
    return out


def _show_phong(args) -> str:
    p, n, eye, light, colour, ambient, ka, kd, ks, s = args
    return (f"point {vec(p)}, normal {vec(n)}, eye {vec(eye)}, light {vec(light)} of colour "
            f"{vec(colour)}, ambient {vec(ambient)}, ka {vec(ka)}, kd {vec(kd)}, ks {vec(ks)}, "
            f"shininess {num(s)}")


TASKS = [
    Task("reflection", "reflect", "ideal reflection", 5, reflection_cases,
         lambda e, g: judge_vector(e, g, "the reflected direction"), _show_reflection),
    Task("refraction", "refract", "refraction (Snell, total internal reflection)", 10,
         refraction_cases, _judge_refraction, _show_refraction, _show_refracted),
    Task("shadow_ray", "in_shadow", "the shadow ray", 10, shadow_cases, judge_exact,
         _show_shadow, explains=False),
    Task("phong", "shade", "Phong at a point", 10, phong_cases,
         lambda e, g: judge_vector(e, g, "the colour"), _show_phong),
]
