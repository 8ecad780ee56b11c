"""The 2D pictures of the course's worked exercises (`raytrace.exercise` solves them): a
matplotlib Figure each; no backend is chosen."""

from __future__ import annotations

import numpy as np

from raytrace.exercise import GLASS_IOR, PlaneSolution, Refraction, as_text, critical_angle


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
    ax.annotate(f"n = {as_text(s.normal)}", s.point + 1.2 * s.unit, xytext=(10, -10),
                textcoords="offset pixels", fontsize=pt, color="#2ab34a", va="top")
    ax.plot(*s.point, "o", ms=text_px * 0.6, color="#444444")
    ax.annotate(f"a = {as_text(s.point)}", s.point, xytext=(-12, 12), textcoords="offset pixels",
                fontsize=pt, ha="right")
    end = s.origin + 1.9 * s.direction if np.isfinite(s.lam) else s.origin + 3 * s.direction
    ax.annotate("", end, s.origin,
                arrowprops=dict(arrowstyle="-|>", lw=3, color="#1e6ee6", mutation_scale=30))
    ax.plot(*s.origin, "s", ms=text_px * 0.6, color="#1e6ee6")
    ax.annotate(f"o = {as_text(s.origin)}", s.origin, xytext=(14, -6), textcoords="offset pixels",
                fontsize=pt, color="#1e6ee6", va="top")
    ax.annotate(f"r = {as_text(s.direction)}", s.origin + 0.5 * s.direction, xytext=(14, 0),
                textcoords="offset pixels", fontsize=pt, color="#1e6ee6")
    if np.isfinite(s.lam):
        ax.plot(*s.hit, "o", ms=text_px * 0.9, mfc="#ffd600", mec="black", mew=2, zorder=5)
        ax.annotate(f"λ = {s.lam:g}:  x = {as_text(s.hit)}", s.hit, xytext=(28, 4),
                    textcoords="offset pixels", fontsize=pt, weight="bold")
    ax.legend(loc="lower right", fontsize=pt * 0.9)
    return fig


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
