"""Counting along one eye ray, in a 2D side view: which shadow-volume faces the ray crosses,
each with its +1/-1, for z-pass (faces between the eye and the surface) and z-fail (faces
behind the surface, out to infinity), in the textbook's counting (the occluder's silhouette
volume: one closed occluder counts 1) and in ours (every edge casts: it counts 2).

2D stands in for a cut through the scene: points are (x, y), y up, the floor is y = 0, an
occluder is a closed polygon, and a volume face is a segment (a near cap), a ray from L's far
side of a vertex (a side), or the far cap at infinity.  A crossing is "entering" when the ray
meets the face's outside first (d . n < 0, n the outward normal).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

EPS = 1e-12   # |cross product| below which a ray and a face count as parallel


@dataclass(frozen=True)
class Face:
    """A boundary face of a 2D shadow volume.

    kind   : "near cap", "side" or "far cap"
    a      : (2,) start point (for the far cap: unused)
    d      : (2,) a segment's end minus its start, or a side ray's direction (to infinity)
    normal : (2,) outward normal (the far cap: unused)
    ray    : True for a side (a ray from a, length infinite)
    weight : how many copies (the multiplicity: 2 on our silhouette sides)
    wedge  : for the far cap, the two bounding directions (2, 2): the directions at infinity
             inside the volume
    """

    kind: str
    a: np.ndarray
    d: np.ndarray
    normal: np.ndarray
    ray: bool = False
    weight: int = 1
    wedge: np.ndarray | None = None


@dataclass(frozen=True)
class Crossing:
    t: float            # along the eye ray, in units of its direction (the surface is t = 1)
    point: np.ndarray   # (2,), np.inf components for the far cap
    face: Face
    entering: bool

    @property
    def step(self) -> int:
        """+weight entering, -weight leaving (the z-pass sign of this crossing)."""
        return self.face.weight if self.entering else -self.face.weight


def _perp(v: np.ndarray) -> np.ndarray:
    return np.array([-v[1], v[0]])


def _cross(a: np.ndarray, b: np.ndarray) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def segment_volume(light: np.ndarray, a: np.ndarray, b: np.ndarray) -> list[Face]:
    """The shadow volume of segment (a, b) lit from `light`: the segment as near cap, a side
    ray from each end away from the light, the far cap at infinity."""
    faces = [Face("near cap", a, b - a, _outward(_perp(b - a), light - a))]
    for p, q in ((a, b), (b, a)):
        d = p - light
        faces.append(Face("side", p, d, _outward(_perp(d), p - q), ray=True))
    faces.append(Face("far cap", a, np.zeros(2), np.zeros(2),
                      wedge=np.array([a - light, b - light])))
    return faces


def _outward(n: np.ndarray, toward: np.ndarray) -> np.ndarray:
    """n, flipped to point along `toward`, unit length."""
    n = n / np.linalg.norm(n)
    return n if n @ toward > 0 else -n


def textbook_volume(light: np.ndarray, polygon: np.ndarray) -> list[Face]:
    """The silhouette volume of a closed convex polygon ((k, 2), in order): near caps are its
    edges facing the light, sides the rays through its two silhouette vertices."""
    k = len(polygon)
    centre = polygon.mean(axis=0)
    faces = []
    for i in range(k):
        a, b = polygon[i], polygon[(i + 1) % k]
        n = _outward(_perp(b - a), a - centre)           # the polygon's outward normal
        if n @ (light - a) > 0:                          # faces the light
            faces.append(Face("near cap", a, b - a, n))
    dirs = polygon - light
    angles = np.arctan2(dirs[:, 1], dirs[:, 0])
    ref = np.arctan2(*(centre - light)[::-1])
    rel = (angles - ref + np.pi) % (2 * np.pi) - np.pi
    lo, hi = polygon[np.argmin(rel)], polygon[np.argmax(rel)]
    for p, q in ((lo, hi), (hi, lo)):
        d = p - light
        faces.append(Face("side", p, d, _outward(_perp(d), p - q), ray=True))
    faces.append(Face("far cap", lo, np.zeros(2), np.zeros(2),
                      wedge=np.array([lo - light, hi - light])))
    return faces


def ours_volume(light: np.ndarray, polygon: np.ndarray) -> list[Face]:
    """Every edge of the polygon casts (two-sided surfaces), summed by the multiplicity rule:
    every edge a near cap, the sides through the two silhouette vertices twice, the sides
    through the other vertices cancelled, the far cap twice."""
    faces = []
    k = len(polygon)
    for i in range(k):
        a, b = polygon[i], polygon[(i + 1) % k]
        faces.append(segment_volume(light, a, b)[0])
    for f in textbook_volume(light, polygon):
        if f.kind != "near cap":
            faces.append(Face(f.kind, f.a, f.d, f.normal, f.ray, 2, f.wedge))
    return faces


def crossings(eye: np.ndarray, surface: np.ndarray, faces: list[Face]) -> list[Crossing]:
    """Every crossing of the ray eye + t (surface - eye), t > 0, with `faces`, in order of t;
    the far cap (t = inf) last, when the ray's direction lies inside its wedge."""
    d = surface - eye
    out = []
    for f in faces:
        if f.kind == "far cap":
            u, v = f.wedge
            inside = _cross(u, d) * _cross(u, v) > 0 and _cross(d, v) * _cross(u, v) > 0
            if inside:   # the ray ends inside the volume's cone: it leaves through the far cap
                out.append(Crossing(np.inf, np.full(2, np.inf), f, entering=False))
            continue
        den = _cross(d, f.d)
        if abs(den) < EPS:
            continue
        w = f.a - eye
        t, s = _cross(w, f.d) / den, _cross(w, d) / den
        if t > 0 and s >= 0 and (f.ray or s <= 1):
            out.append(Crossing(t, eye + t * d, f, entering=float(d @ f.normal) < 0))
    return sorted(out, key=lambda c: c.t)


@dataclass(frozen=True)
class Counts:
    zpass: int       # the sum over crossings before the surface (t < 1)
    zfail: int       # the count at the surface from infinity: -(sum over crossings t > 1)
    inside_eye: int  # how many volumes (weighted) hold the eye: zpass = zfail - inside_eye


def counts(cs: list[Crossing]) -> Counts:
    zpass = sum(c.step for c in cs if c.t < 1)
    zfail = -sum(c.step for c in cs if c.t > 1)
    return Counts(zpass, zfail, zfail - zpass)


# ---------------------------------------------------------------------------------------------
# The lecture's scene and its picture
# ---------------------------------------------------------------------------------------------

LIGHT = np.array([0.0, 6.0])
BOX = np.array([[0.6, 3.0], [1.9, 3.0], [1.9, 3.9], [0.6, 3.9]])
CASES = (  # (name, eye, surface point on the floor)
    ("eye outside every volume", np.array([-3.6, 2.3]), np.array([2.6, 0.0])),
    ("eye inside the volume", np.array([2.0, 2.1]), np.array([2.7, 0.0])),
)
VIEW = (-4.2, 7.4, -2.6, 6.7)   # x0, x1, y0, y1


def diagram(width: int, height: int, text_px: int):
    """A matplotlib Figure (width x height pixels): one panel per case, the textbook volume
    shaded, the eye ray with every crossing numbered with its textbook / our step, and the
    sums.  Returns the figure and, per case, (textbook Counts, our Counts)."""
    from matplotlib.figure import Figure

    dpi = 100
    pt = text_px * 72 / dpi
    fig = Figure(figsize=(width / dpi, height / dpi), dpi=dpi)
    fig.subplots_adjust(left=0.01, right=0.99, top=0.86, bottom=0.17, wspace=0.04)
    results = []
    for k, (name, eye, surface) in enumerate(CASES):
        ax = fig.add_subplot(1, len(CASES), k + 1)
        tb, ours = textbook_volume(LIGHT, BOX), ours_volume(LIGHT, BOX)
        _draw_case(ax, tb, eye, surface, text_px, pt)
        ctb, cours = crossings(eye, surface, tb), crossings(eye, surface, ours)
        _label_crossings(ax, eye, surface, ctb, cours, text_px, pt)
        a, b = counts(ctb), counts(cours)
        results.append((a, b))
        ax.set_title(name, fontsize=pt)
        truth = "P is in shadow" if b.zfail > 0 else "P is lit"
        verdict = "right" if a.zpass == a.zfail else "WRONG: says lit"
        ax.text(0.5, -0.03,
                f"z-pass (eye → P): {a.zpass} / {b.zpass}   {verdict}\n"
                f"z-fail (P → ∞): {a.zfail} / {b.zfail}   {truth}",
                transform=ax.transAxes, fontsize=pt, va="top", ha="center",
                color="#c81e28" if a.zpass != a.zfail else "black")
    fig.text(0.5, 0.97, "every crossing: textbook / ours  (entering +1, leaving −1 from the "
             "eye; z-fail counts the faces behind P the other way round)",
             ha="center", va="top", fontsize=pt * 0.9)
    return fig, results


def _draw_case(ax, tb, eye: np.ndarray, surface: np.ndarray, text_px: int, pt: float) -> None:
    """One panel's scene: the textbook volume `tb` cut to the view (the box and the wedge
    behind it), the floor, the light, and the eye ray to P (solid) and on behind it (dashed)."""
    from matplotlib.patches import Polygon

    x0, x1, y0, y1 = VIEW
    ax.set_xlim(x0, x1), ax.set_ylim(y0, y1), ax.set_aspect("equal"), ax.axis("off")
    sides = [f for f in tb if f.kind == "side"]
    far = 40.0
    wedge = [sides[0].a, sides[0].a + far * sides[0].d, sides[1].a + far * sides[1].d,
             sides[1].a]
    ax.add_patch(Polygon(np.array(wedge), closed=True, color="#bbbbbb", alpha=0.45, lw=0))
    ax.add_patch(Polygon(BOX, closed=True, fc="#4a5aa0", ec="black", lw=1.5, zorder=3))
    ax.fill_between([x0, x1], y0, 0, color="#e8dcc8", zorder=1)
    ax.plot([x0, x1], [0, 0], color="#6b5a3a", lw=3, zorder=2)
    ax.text(x1 - 0.15, -0.35, "floor", ha="right", va="top", fontsize=pt * 0.9,
            color="#6b5a3a")
    ax.text(x0 + 0.15, -0.35, "behind P: z-fail counts here", ha="left",
            va="top", fontsize=pt * 0.9, color="#6b5a3a")
    for f in sides:
        ax.plot(*np.array([f.a, f.a + far * f.d]).T, color="#f5a000", lw=3, zorder=2)
    for f in tb:
        if f.kind == "near cap":
            ax.plot(*np.array([f.a, f.a + f.d]).T, color="#2ab34a", lw=5, zorder=4)
    ax.plot(*LIGHT, "o", ms=text_px * 0.9, mfc="#ffd600", mec="black", mew=2, zorder=6)
    ax.annotate("L", LIGHT, xytext=(text_px * 0.8, 0), textcoords="offset pixels",
                fontsize=pt, va="center", weight="bold")
    d = surface - eye
    beyond = eye + 3.0 * d
    ax.plot(*np.array([eye, surface]).T, color="#1e6ee6", lw=3, zorder=5)
    ax.plot(*np.array([surface, beyond]).T, color="#1e6ee6", lw=2, ls="--", zorder=5)
    ax.plot(*eye, "s", ms=text_px * 0.7, mfc="#1e6ee6", mec="black", zorder=6)
    ax.annotate("eye", eye, xytext=(-text_px * 0.6, text_px * 0.8),
                textcoords="offset pixels", fontsize=pt, ha="right")
    ax.plot(*surface, "o", ms=text_px * 0.5, mfc="white", mec="#1e6ee6", mew=2, zorder=6)
    ax.annotate("P", surface, xytext=(text_px * 0.4, text_px * 0.3),
                textcoords="offset pixels", fontsize=pt, weight="bold")


def _label_crossings(ax, eye: np.ndarray, surface: np.ndarray, ctb, cours, text_px: int,
                     pt: float) -> None:
    """Mark the textbook's crossings `ctb` of the eye ray, each labelled with both steps,
    textbook / ours (`cours`: the same faces, ours weigh 2); one off the view (or the far cap
    at infinity) at the view's edge."""
    x0, x1, y0, y1 = VIEW
    d = surface - eye
    steps = {}
    for c in cours:
        key = (round(c.t, 9) if np.isfinite(c.t) else np.inf)
        steps[key] = steps.get(key, 0) + c.step
    for c in ctb:
        key = round(c.t, 9) if np.isfinite(c.t) else np.inf
        behind = c.t > 1   # z-fail counts these, with the opposite sign
        ours_step = steps.get(key, 0)
        value, ours_value = (-c.step, -ours_step) if behind else (c.step, ours_step)
        label = f"{value:+d} / {ours_value:+d}"
        p = c.point if np.isfinite(c.t) else None
        if p is None or not (x0 < p[0] < x1 and y0 < p[1] < y1):
            p = eye + _edge_t(eye, d, VIEW) * d
            label = ("far cap at ∞  " if not np.isfinite(c.t) else "off view  ") + label
        colour = "#00873c" if value > 0 else "#c81e28"
        right = p[0] > (x0 + x1) / 2
        low = behind and p[1] > y0 + 1.0      # room below the point for its label
        ax.plot(*p, "X", ms=text_px * 0.6, color=colour, mec="black", zorder=7)
        ax.annotate(label, p, xytext=(-text_px * 0.6 if right else text_px * 0.6,
                                      -text_px * 1.2 if low else text_px * 0.9),
                    textcoords="offset pixels", fontsize=pt * 0.9, color=colour,
                    weight="bold", zorder=8, ha="right" if right else "left",
                    bbox=dict(fc="white", ec=colour, alpha=0.9, boxstyle="round"))


def _edge_t(eye: np.ndarray, d: np.ndarray, view) -> float:
    """The largest t at which eye + t d is still inside the view box."""
    x0, x1, y0, y1 = view
    ts = []
    for lo, hi, o, v in ((x0, x1, eye[0], d[0]), (y0, y1, eye[1], d[1])):
        if v > 0:
            ts.append((hi - o) / v)
        elif v < 0:
            ts.append((lo - o) / v)
    return 0.97 * min(ts)
