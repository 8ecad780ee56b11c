"""The course's worked exercises, solved with the ray tracer's own formulas (`intersect`):

    raytrace exercise plane   the ray (5,1) + λ(−1,3) against the plane (in 2D: the line)
                              through (2,2) with normal (1,−1): λ = 1, the point (4,4)
    raytrace exercise tir     Snell's law at a glass-air surface, up to and past the critical
                              angle (total internal reflection)

Each has a `solve_*` returning the numbers and a `*_text` printing the worked solution step by
step; the 2D pictures of them are the course's (`shadowvol.course.exercise_picture`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .intersect import hesse, ray_plane, refract

PLANE_ORIGIN = (5.0, 1.0)
PLANE_DIRECTION = (-1.0, 3.0)
PLANE_POINT = (2.0, 2.0)
PLANE_NORMAL = (1.0, -1.0)

GLASS_IOR = 1.5
TIR_ANGLES = (20.0, 35.0, 45.0, 60.0)   # incidence angles inside the glass, degrees


@dataclass(frozen=True)
class PlaneSolution:
    origin: np.ndarray      # (2,) o
    direction: np.ndarray   # (2,) r
    point: np.ndarray       # (2,) a, on the plane
    normal: np.ndarray      # (2,) n as given
    unit: np.ndarray        # (2,) n / |n|
    distance: float         # d of the Hesse form n·x = d
    n_dot_o: float
    n_dot_r: float
    lam: float              # λ = (d − n·o) / (n·r)
    hit: np.ndarray         # (2,) o + λ r


def solve_plane(origin=PLANE_ORIGIN, direction=PLANE_DIRECTION, point=PLANE_POINT,
                normal=PLANE_NORMAL) -> PlaneSolution:
    """The ray o + λ r against the plane through `point` with normal `normal`, by the
    ray tracer's `hesse` and `ray_plane` (λ = inf for a miss)."""
    o, r = np.asarray(origin, float), np.asarray(direction, float)
    unit, d = hesse(point, normal)
    lam = float(ray_plane(o[None], r[None], unit, d)[0])
    return PlaneSolution(o, r, np.asarray(point, float), np.asarray(normal, float), unit, d,
                         float(unit @ o), float(unit @ r), lam, o + lam * r)


def as_text(v) -> str:
    """A vector as the worked solutions print it: "(x, y)", to 6 decimals, %g."""
    return "(" + ", ".join(f"{x:g}" for x in np.round(v, 6)) + ")"


def plane_text(s: PlaneSolution) -> str:
    """The worked solution, step by step."""
    n_len = float(np.linalg.norm(s.normal))
    a_n = float(s.normal @ s.point)
    lines = [
        f"Ray:   x(λ) = o + λ r = {as_text(s.origin)} + λ {as_text(s.direction)},  λ >= 0",
        f"Plane: through a = {as_text(s.point)} with normal n = {as_text(s.normal)}",
        "",
        "1. Hesse normal form n0·x = d, with n0 = n / |n| and d = n0·a:",
        f"   |n| = {n_len:.6g},  n0 = {as_text(s.unit)},  d = {a_n:g} / {n_len:.6g} = "
        f"{s.distance:g}",
        f"   (here: {s.normal[0]:g}·x {'+' if s.normal[1] >= 0 else '−'} "
        f"{abs(s.normal[1]):g}·y = {a_n:g})",
        "2. Put the ray into it:  n0·(o + λ r) = d   =>   λ = (d − n0·o) / (n0·r)",
        f"   n0·o = {s.n_dot_o:.6g},  n0·r = {s.n_dot_r:.6g}",
    ]
    if not np.isfinite(s.lam):
        lines.append("   n0·r = 0 or λ <= 0: the ray misses the plane")
        return "\n".join(lines)
    lines += [
        f"   λ = ({s.distance:g} − {s.n_dot_o:.6g}) / ({s.n_dot_r:.6g}) = {s.lam:g}",
        f"3. The point: x({s.lam:g}) = {as_text(s.origin)} + {s.lam:g} {as_text(s.direction)} = "
        f"{as_text(s.hit)}",
        f"   check: n·x − n·a = {float(s.normal @ s.hit - a_n):g}  (on the plane)",
        "   λ > 0: the hit lies ahead of the ray's origin",
    ]
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# Total internal reflection
# ---------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Refraction:
    angle: float            # incidence, degrees, inside the glass
    direction: np.ndarray   # (2,) the incoming direction (unit)
    out: np.ndarray         # (2,) refracted (or, when tir, reflected) direction
    tir: bool
    out_angle: float        # degrees from the normal of the outgoing ray


def critical_angle(ior: float = GLASS_IOR) -> float:
    """Degrees: sin θc = 1 / ior (glass to air)."""
    return float(np.degrees(np.arcsin(1.0 / ior)))


def solve_tir(angles=TIR_ANGLES, ior: float = GLASS_IOR) -> list[Refraction]:
    """Rays inside glass (below y = 0) meeting the glass-air surface y = 0 at `angles`, by the
    ray tracer's `refract` (eta = ior / 1)."""
    th = np.radians(np.asarray(angles, float))
    d = np.stack([np.sin(th), np.cos(th), np.zeros_like(th)], axis=1)     # upward, to the right
    n = np.tile([0.0, -1.0, 0.0], (len(th), 1))                          # facing the ray
    out, tir = refract(d, n, ior)
    return [Refraction(float(a), d[i, :2], out[i, :2], bool(tir[i]),
                       float(np.degrees(np.arccos(abs(out[i, 1])))))
            for i, a in enumerate(angles)]


def tir_text(rays: list[Refraction], ior: float = GLASS_IOR) -> str:
    lines = [f"Glass (n1 = {ior:g}) to air (n2 = 1): Snell  n1 sin θ1 = n2 sin θ2",
             f"critical angle θc = asin(n2 / n1) = {critical_angle(ior):.2f}°", ""]
    for r in rays:
        s2 = ior * np.sin(np.radians(r.angle))
        if r.tir:
            lines.append(f"θ1 = {r.angle:4.1f}°: sin θ2 = {s2:.3f} > 1: total internal "
                         f"reflection, the ray stays in the glass at {r.out_angle:.1f}°")
        else:
            lines.append(f"θ1 = {r.angle:4.1f}°: sin θ2 = {s2:.3f}, θ2 = {r.out_angle:.1f}°: "
                         "refracted into the air")
    return "\n".join(lines)
