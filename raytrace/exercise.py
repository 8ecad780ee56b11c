"""The course's worked exercises, solved with the ray tracer's own formulas (`intersect`):

    raytrace exercise plane   the ray (5,1) + λ(−1,3) against the plane (in 2D: the line)
                              through (2,2) with normal (1,−1): λ = 1, the point (4,4)
    raytrace exercise tir     Snell's law at a glass-air surface, up to and past the critical
                              angle (total internal reflection)

Each has a `solve_*` returning the numbers, a `*_text` printing the worked solution step by
step, and a `*_figure` drawing the 2D picture (a matplotlib Figure; no backend is chosen).
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


def _v(v) -> str:
    return "(" + ", ".join(f"{x:g}" for x in np.round(v, 6)) + ")"


def plane_text(s: PlaneSolution) -> str:
    """The worked solution, step by step."""
    n_len = float(np.linalg.norm(s.normal))
    a_n = float(s.normal @ s.point)
    lines = [
        f"Ray:   x(λ) = o + λ r = {_v(s.origin)} + λ {_v(s.direction)},  λ >= 0",
        f"Plane: through a = {_v(s.point)} with normal n = {_v(s.normal)}",
        "",
        "1. Hesse normal form n0·x = d, with n0 = n / |n| and d = n0·a:",
        f"   |n| = {n_len:.6g},  n0 = {_v(s.unit)},  d = {a_n:g} / {n_len:.6g} = "
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
        f"3. The point: x({s.lam:g}) = {_v(s.origin)} + {s.lam:g} {_v(s.direction)} = "
        f"{_v(s.hit)}",
        f"   check: n·x − n·a = {float(s.normal @ s.hit - a_n):g}  (on the plane)",
        "   λ > 0: the hit lies ahead of the ray's origin",
    ]
    return "\n".join(lines)


def plane_figure(s: PlaneSolution, width_px: int = 1200, height_px: int = 900,
                 text_px: float = 20):
    """The exercise in 2D: the plane's line with its normal at a, the ray from o along r, the
    hit at λ, labelled."""
    from matplotlib.figure import Figure

    dpi = 100
    pt = text_px * 72 / dpi
    fig = Figure(figsize=(width_px / dpi, height_px / dpi), dpi=dpi)
    ax = fig.add_axes([0.07, 0.08, 0.9, 0.88])
    lo, hi = -0.5, 7.0
    ax.set_xlim(lo, hi), ax.set_ylim(lo, hi), ax.set_aspect("equal")
    ax.grid(True, color="#dddddd"), ax.tick_params(labelsize=pt * 0.8)
    tangent = np.array([-s.unit[1], s.unit[0]])
    line = np.array([s.point - 20 * tangent, s.point + 20 * tangent])
    ax.plot(*line.T, color="#444444", lw=3, label=f"plane n0·x = {s.distance:g}")
    ax.annotate("", s.point + 1.2 * s.unit, s.point,
                arrowprops=dict(arrowstyle="-|>", lw=3, color="#2ab34a", mutation_scale=30))
    ax.annotate(f"n = {_v(s.normal)}", s.point + 1.2 * s.unit, xytext=(10, -10),
                textcoords="offset pixels", fontsize=pt, color="#2ab34a", va="top")
    ax.plot(*s.point, "o", ms=text_px * 0.6, color="#444444")
    ax.annotate(f"a = {_v(s.point)}", s.point, xytext=(-12, 12), textcoords="offset pixels",
                fontsize=pt, ha="right")
    end = s.origin + 1.9 * s.direction if np.isfinite(s.lam) else s.origin + 3 * s.direction
    ax.annotate("", end, s.origin,
                arrowprops=dict(arrowstyle="-|>", lw=3, color="#1e6ee6", mutation_scale=30))
    ax.plot(*s.origin, "s", ms=text_px * 0.6, color="#1e6ee6")
    ax.annotate(f"o = {_v(s.origin)}", s.origin, xytext=(14, -6), textcoords="offset pixels",
                fontsize=pt, color="#1e6ee6", va="top")
    ax.annotate(f"r = {_v(s.direction)}", s.origin + 0.5 * s.direction, xytext=(14, 0),
                textcoords="offset pixels", fontsize=pt, color="#1e6ee6")
    if np.isfinite(s.lam):
        ax.plot(*s.hit, "o", ms=text_px * 0.9, mfc="#ffd600", mec="black", mew=2, zorder=5)
        ax.annotate(f"λ = {s.lam:g}:  x = {_v(s.hit)}", s.hit, xytext=(28, 4),
                    textcoords="offset pixels", fontsize=pt, weight="bold")
    ax.legend(loc="lower right", fontsize=pt * 0.9)
    return fig


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


def tir_figure(rays: list[Refraction], ior: float = GLASS_IOR, width_px: int = 1200,
               height_px: int = 800, text_px: float = 20):
    """All rays meeting the surface at one point: refracted ones bent away from the normal
    into the air, the ones past the critical angle reflected back into the glass."""
    from matplotlib.figure import Figure

    dpi = 100
    pt = text_px * 72 / dpi
    fig = Figure(figsize=(width_px / dpi, height_px / dpi), dpi=dpi)
    ax = fig.add_axes([0.01, 0.01, 0.98, 0.98])
    ax.set_xlim(-2.9, 4.4), ax.set_ylim(-2.5, 2.5), ax.set_aspect("equal"), ax.axis("off")
    ax.fill_between([-3, 4.4], -2.5, 0, color="#cfeaf5")
    ax.text(4.3, -2.4, f"glass, n = {ior:g}", fontsize=pt, va="bottom", ha="right")
    ax.text(-2.8, 2.4, "air, n = 1", fontsize=pt, va="top")
    ax.plot([0, 0], [-2.4, 2.4], ls=":", color="#555555", lw=2)
    colours = ["#1e6ee6", "#00a0a0", "#e08000", "#c81e28"]
    for r, c in zip(rays, colours):
        start = -min(2.3 / abs(r.direction[1]), 2.8 / max(abs(r.direction[0]), 1e-9)) \
            * r.direction
        ax.plot([start[0], 0], [start[1], 0], color=c, lw=3)
        out = r.out * 2.0
        ax.annotate("", out, (0, 0), arrowprops=dict(arrowstyle="-|>", lw=3, color=c,
                                                     ls="--" if r.tir else "-",
                                                     mutation_scale=25))
        what = "totally reflected" if r.tir else f"out at {r.out_angle:.1f}°"
        ax.annotate(f"in at {r.angle:g}°, {what}", out, xytext=(10, 0),
                    textcoords="offset pixels", fontsize=pt * 0.9, color=c, ha="left",
                    va="center")
    tc = np.radians(critical_angle(ior))
    crit = -2.3 * np.array([np.sin(tc), np.cos(tc)]) / np.cos(tc)
    ax.plot([crit[0], 0], [crit[1], 0], color="black", lw=1.5, ls="-.")
    ax.annotate(f"critical angle {np.degrees(tc):.1f}°", 0.45 * crit, xytext=(-2.8, -0.6),
                textcoords="data", fontsize=pt * 0.9, ha="left", va="center",
                arrowprops=dict(arrowstyle="-", lw=1, color="black"))
    return fig
