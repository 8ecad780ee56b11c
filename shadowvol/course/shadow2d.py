"""The course's 2D exercise: shadow polygons of segments lit by a point light in the unit square.

The world is the unit square [0, 1] x [0, 1].  Objects are segments (v_a, v_b) taken from outlines
whose vertices are listed counter-clockwise (CCW), so every segment has an OUTWARD NORMAL: the
right-hand perpendicular of its direction,

    d = v_b - v_a,    n = (d_y, -d_x) / |d|

(for the CCW square (0,0) -> (1,0) -> (1,1) -> (0,1) the bottom edge gets n = (0, -1): outward).
A segment is FRONT-facing when the light L is on the side its normal points to, n . (L - v_a) > 0,
BACK-facing when n . (L - v_a) < 0, and seen EDGE-ON when L lies on the segment's line.

The shadow of one segment, as the course builds it, is bounded by its SHADOW POLYGONS (in 2D they
are segments): the segment itself and the two rays from L through its end points, each extended
from the end point until it reaches the square's border.  The shadow REGION is what they enclose
together with the part of the border between the two rays; it is the set of points X of the square
for which the segment L -> X crosses the occluder, and it is always convex (the wedge from L,
beyond the occluder's line, inside the square).  It includes the square's corners where it wraps
around them.

Orientation, one rule for everything: a region's vertices and its shadow polygons are listed CCW
around the region, and every reported normal is the unit right-hand perpendicular of start -> end,
exactly as for the input segments.  So every shadow-polygon normal points OUT of the shadow region;
the occluder's own shadow polygon is listed from the end point that makes its normal point at the
light (for a back-facing segment it runs v_b -> v_a).  This is the 2D picture of the shadow-volume
rule "front faces of the volume increment, back faces decrement": the normal tells a ray coming
from the eye whether it enters the shadow (against the normal) or leaves it (along the normal).

Degenerate cases (L exactly on a segment's line, within ON_LINE_TOLERANCE) give a shadow of zero
area, and this module reports them with NO shadow polygons and an empty region (shape (0, 2)):
- "edge-on": L on the line, outside the segment.  The segment hides only the continuation of its
  own line from its far end point to the border: a set of zero area, which no point test with a
  tolerance would ever count as shadowed.
- "contains-light": L on the closed segment itself (including an end point).  The rays from L
  through the end points are the segment's own line again (or undefined, at an end point), so
  again the hidden set has zero area.

Back faces are the caller's choice (`back_faces`): True (the default) treats every segment as a
two-sided occluder, as a lone wall is; False lets only front-facing segments cast, as the course
does for closed outlines, where the shadow of a back-facing edge outside the object lies inside
the shadows of the front-facing ones (the light ray enters the object through a front edge first).
That argument needs the light OUTSIDE the closed outline: with L inside, every edge is back-facing.

Pure numpy; `draw_shadow2d` uses matplotlib (no pyplot: no global figure state).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# Distance from L to a segment's line (in units of the square) at or below which the segment is
# treated as seen edge-on: the shadow wedge would then be thinner than rounding can resolve.
ON_LINE_TOLERANCE = 1e-9
# Perimeter-parameter gap below which a border point counts as sitting on a square corner (so the
# corner is not inserted again as a separate, duplicate region vertex).
CORNER_TOLERANCE = 1e-12
# How far outside [0, 1] an input coordinate may be and still count as inside the square.
SQUARE_TOLERANCE = 1e-12

FRONT, BACK, EDGE_ON, CONTAINS_LIGHT = "front", "back", "edge-on", "contains-light"

# The square's corners in CCW order; corner k sits at perimeter parameter s = k (see `_perimeter`).
SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
SQUARE.setflags(write=False)


@dataclass(frozen=True, eq=False)
class ShadowSegment:
    """One shadow polygon (a segment in 2D).

    start, end : (2,) float64, CCW along the shadow region's boundary
    normal     : (2,) float64, unit, pointing out of the shadow region (right of start -> end)
    kind       : "occluder" (the casting segment itself) or "ray" (from an end point, away from
                 the light, to the square's border; zero length when the end point is on the border)
    """

    start: np.ndarray
    end: np.ndarray
    normal: np.ndarray
    kind: str


@dataclass(frozen=True, eq=False)
class SegmentShadow:
    """The shadow of input segment `index`.

    facing   : FRONT, BACK, EDGE_ON or CONTAINS_LIGHT (see the module docstring)
    polygons : (occluder, ray from its end, ray back to its start), or () when nothing is cast
    region   : (k, 2) float64, the convex shadow region CCW (k >= 3), or (0, 2) when it has no area
               or the segment does not cast (a back face with back_faces=False)
    """

    index: int
    facing: str
    polygons: tuple[ShadowSegment, ...]
    region: np.ndarray

    @property
    def casts(self) -> bool:
        return len(self.region) > 0


def as_segments(segments) -> np.ndarray:
    s = np.asarray(segments, dtype=np.float64)
    if s.ndim == 2 and s.shape[1] == 4:
        s = s.reshape(-1, 2, 2)
    if s.ndim != 3 or s.shape[1:] != (2, 2):
        raise ValueError(f"segments must be (n, 2, 2) (or (n, 4)) numbers, got shape {s.shape}")
    if not np.isfinite(s).all():
        raise ValueError("segments contain non-finite numbers")
    if ((s < -SQUARE_TOLERANCE) | (s > 1 + SQUARE_TOLERANCE)).any():
        raise ValueError("every segment must lie inside the unit square [0, 1] x [0, 1]")
    zero = np.flatnonzero(np.all(s[:, 0] == s[:, 1], axis=1))
    if zero.size:
        raise ValueError(f"segment {int(zero[0])} has zero length")
    return np.clip(s, 0.0, 1.0)


def as_light(light) -> np.ndarray:
    L = np.asarray(light, dtype=np.float64)
    if L.shape != (2,) or not np.isfinite(L).all():
        raise ValueError(f"the light must be two finite numbers, got {light!r}")
    if ((L < -SQUARE_TOLERANCE) | (L > 1 + SQUARE_TOLERANCE)).any():
        raise ValueError(f"the light {L.tolist()} is outside the unit square")
    return np.clip(L, 0.0, 1.0)


def polygon_segments(vertices) -> np.ndarray:
    """(k, 2) outline vertices (CCW, not repeating the first) -> (k, 2, 2) closed segments."""
    v = np.asarray(vertices, dtype=np.float64)
    if v.ndim != 2 or v.shape[1] != 2 or len(v) < 2:
        raise ValueError(f"an outline needs (k, 2) vertices with k >= 2, got shape {v.shape}")
    return np.stack([v, np.roll(v, -1, axis=0)], axis=1)


def outward_normals(segments) -> np.ndarray:
    """(n, 2, 2) segments -> (n, 2) float64 unit outward normals (right of v_a -> v_b)."""
    s = as_segments(segments)
    d = s[:, 1] - s[:, 0]
    n = np.stack([d[:, 1], -d[:, 0]], axis=1)
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def classify(light, segments) -> np.ndarray:
    """(n,) array of FRONT / BACK / EDGE_ON / CONTAINS_LIGHT for each segment, seen from `light`."""
    L, s = as_light(light), as_segments(segments)
    side = np.einsum("ij,ij->i", outward_normals(s), L - s[:, 0])   # signed distance of L
    d = s[:, 1] - s[:, 0]
    t = np.einsum("ij,ij->i", L - s[:, 0], d) / np.einsum("ij,ij->i", d, d)
    on_line = np.abs(side) <= ON_LINE_TOLERANCE
    # On the line, L is on the closed segment when its parameter t along v_a -> v_b is in [0, 1]
    # (up to the same tolerance, measured as a length).
    length = np.linalg.norm(d, axis=1)
    within = (t * length >= -ON_LINE_TOLERANCE) & ((t - 1) * length <= ON_LINE_TOLERANCE)
    out = np.where(side > 0, FRONT, BACK).astype(object)
    out[on_line & within] = CONTAINS_LIGHT
    out[on_line & ~within] = EDGE_ON
    return out


def border_exit(origins, directions) -> tuple[np.ndarray, np.ndarray]:
    """Where rays from inside the square leave it.

    origins : (n, 2) float64 inside the closed square; directions : (n, 2) float64, non-zero.
    Returns points (n, 2) float64 exactly on the border, and their perimeter parameters s (n,)
    in [0, 4): s = x on the bottom side, 1 + y on the right, 2 + (1 - x) on the top, 3 + (1 - y)
    on the left, so that s grows CCW and corner k of SQUARE sits at s = k.
    """
    o = np.asarray(origins, dtype=np.float64)
    d = np.asarray(directions, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_side = np.where(d > 0, (1.0 - o) / d, np.where(d < 0, -o / d, np.inf))
    t_side = np.maximum(t_side, 0.0)          # an origin on the border leaves at once
    axis = np.argmin(t_side, axis=1)
    t = t_side[np.arange(len(o)), axis]
    p = np.clip(o + t[:, None] * d, 0.0, 1.0)
    rows = np.arange(len(o))
    hit_high = d[rows, axis] > 0
    p[rows, axis] = np.where(hit_high, 1.0, 0.0)  # exactly on the side it crossed
    x, y = p[:, 0], p[:, 1]
    s = np.select([(axis == 0) & hit_high, (axis == 1) & hit_high, axis == 0],
                  [1.0 + y, 2.0 + (1.0 - x), 3.0 + (1.0 - y)], default=x)
    return p, np.mod(s, 4.0)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _right(v: np.ndarray) -> np.ndarray:
    """Right-hand perpendicular (v_y, -v_x): the outward normal of a CCW boundary edge."""
    return np.stack([v[..., 1], -v[..., 0]], axis=-1)


def _corners_between(s_from: float, s_to: float) -> np.ndarray:
    """The square's corners passed walking CCW along the border from s_from to s_to, in order."""
    arc = (s_to - s_from) % 4.0
    offsets = (np.arange(4.0) - s_from) % 4.0
    keep = (offsets > CORNER_TOLERANCE) & (offsets < arc - CORNER_TOLERANCE)
    return SQUARE[np.flatnonzero(keep)[np.argsort(offsets[keep])]]


def shadow_polygons(light, segments, *, back_faces: bool = True) -> list[SegmentShadow]:
    """The shadow of every segment, lit by a point light, inside the unit square.

    light    : (2,) the light position L, inside the closed square
    segments : (n, 2, 2) [[v_a, v_b], ...] (or (n, 4)), inside the closed square, non-zero length
    back_faces : whether back-facing segments cast (True: every segment is a two-sided occluder)

    Returns one SegmentShadow per segment, in input order.  For a casting segment with end
    points ordered (p, q) so that the occluder's normal points at L, the region is
    [p, q, q', corners..., p'] where q', p' are the border points of the rays L -> q, L -> p.
    """
    L, s = as_light(light), as_segments(segments)
    facing = classify(L, s)
    # Order each segment's end points (p, q) so that p -> q has L on its right: then the
    # region p, q, q', ..., p' is CCW and the occluder's right normal points at the light.
    front = (facing == FRONT)[:, None]
    p = np.where(front, s[:, 0], s[:, 1])
    q = np.where(front, s[:, 1], s[:, 0])
    casts = (facing == FRONT) | ((facing == BACK) & back_faces)
    # The rays only exist where L is off the segment's line; elsewhere use a dummy direction.
    safe = casts[:, None]
    up = np.where(safe, p - L, 1.0)
    uq = np.where(safe, q - L, 1.0)
    far_p, s_p = border_exit(p, up)
    far_q, s_q = border_exit(q, uq)
    n_cap, n_q, n_p = _unit(_right(q - p)), _unit(_right(uq)), _unit(-_right(up))

    out = []
    for i in range(len(s)):
        if not casts[i]:
            out.append(SegmentShadow(i, str(facing[i]), (), np.zeros((0, 2))))
            continue
        polys = (ShadowSegment(p[i], q[i], n_cap[i], "occluder"),
                 ShadowSegment(q[i], far_q[i], n_q[i], "ray"),
                 ShadowSegment(far_p[i], p[i], n_p[i], "ray"))
        region = np.concatenate([[p[i], q[i], far_q[i]], _corners_between(s_q[i], s_p[i]),
                                 [far_p[i]]])
        # A ray of zero length (end point on the border) repeats a vertex: drop the repeat.
        keep = np.any(region != np.roll(region, 1, axis=0), axis=1)
        region = region[keep]
        for arr in (region, *(a for seg in polys for a in (seg.start, seg.end, seg.normal))):
            arr.setflags(write=False)
        out.append(SegmentShadow(i, str(facing[i]), polys, region))
    return out


def inside_convex(points, polygon, tolerance: float = 0.0) -> np.ndarray:
    """(m, 2) points -> (m,) bool: inside the convex CCW `polygon` (k, 2), or on its boundary
    within `tolerance` (a distance; negative to demand strictly inside by that margin)."""
    pts = np.asarray(points, dtype=np.float64)
    poly = np.asarray(polygon, dtype=np.float64)
    if len(poly) < 3:
        return np.zeros(len(pts), bool)
    edge = np.roll(poly, -1, axis=0) - poly                           # (k, 2)
    rel = pts[:, None, :] - poly[None, :, :]                          # (m, k, 2)
    cross = edge[None, :, 0] * rel[..., 1] - edge[None, :, 1] * rel[..., 0]
    return np.all(cross >= -tolerance * np.linalg.norm(edge, axis=1)[None, :], axis=1)


def occluded(points, light, segments) -> np.ndarray:
    """(m, 2) points -> (m, n) bool: segment j lies strictly between the light and point i.

    The direct definition of shadow (does the segment L -> X cross the occluder?), independent of
    the shadow polygons; tests use it as the witness.  Touching counts as not crossing.
    """
    X = np.asarray(points, dtype=np.float64)[:, None, :]               # (m, 1, 2)
    L, s = as_light(light), as_segments(segments)
    a, b = s[None, :, 0], s[None, :, 1]                                 # (1, n, 2)

    def cross(u, v):
        return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]

    # L -> X crosses a -> b iff a, b are strictly on opposite sides of line LX and L, X strictly
    # on opposite sides of line ab.
    ab_sides = cross(X - L, a - L) * cross(X - L, b - L)
    lx_sides = cross(b - a, L - a) * cross(b - a, X - a)
    return (ab_sides < 0) & (lx_sides < 0)


def listing(light, segments, shadows: list[SegmentShadow], digits: int = 4) -> str:
    """The text listing the CLI prints: every segment, its facing and its shadow polygons."""
    L, s = as_light(light), as_segments(segments)
    normals = outward_normals(s)

    def f(v):
        return "(" + ", ".join(f"{x:.{digits}f}" for x in v) + ")"

    lines = [f"light L = {f(L)}"]
    for sh, seg, n in zip(shadows, s, normals):
        lines.append(f"segment {sh.index}: {f(seg[0])} -> {f(seg[1])}  normal {f(n)}  "
                     f"{sh.facing}")
        if not sh.polygons:
            why = {EDGE_ON: "seen edge-on: zero-area shadow",
                   CONTAINS_LIGHT: "the light is on the segment: zero-area shadow",
                   BACK: "back-facing, not cast (front faces only)"}[sh.facing]
            lines.append(f"  no shadow polygons ({why})")
            continue
        lines.append("  shadow polygons (start -> end, normal points out of the shadow):")
        for poly in sh.polygons:
            lines.append(f"    {poly.kind:<8} {f(poly.start)} -> {f(poly.end)}  "
                         f"n = {f(poly.normal)}")
        lines.append("  shadow region (CCW): " + " ".join(f(v) for v in sh.region))
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# The picture
# ---------------------------------------------------------------------------------------------

def example() -> tuple[np.ndarray, np.ndarray]:
    """The teaching example drawn in docs/shadow2d.png: light (2,), segments (n, 2, 2).

    A CCW triangle (two edges front-facing, one back-facing), a lone wall whose shadow wraps
    around the top-left corner, a segment seen edge-on and a back-facing wall.
    """
    light = np.array([0.45, 0.35])
    triangle = polygon_segments([[0.58, 0.50], [0.84, 0.53], [0.68, 0.74]])
    wall = np.array([[[0.25, 0.48], [0.38, 0.55]]])          # front-facing (normal toward L)
    edge_on = np.array([[[0.15, 0.35], [0.30, 0.35]]])        # on the line y = 0.35 through L
    back = np.array([[[0.40, 0.18], [0.55, 0.15]]])          # normal points away from L
    return light, np.concatenate([triangle, wall, edge_on, back])


def draw_shadow2d(light, segments, shadows: list[SegmentShadow] | None = None, *,
                  size_px: int = 800, title: str | None = None,
                  normal_length: float = 0.06, font_px: float | None = None) -> np.ndarray:
    """A picture of the exercise: (size_px, size_px, 3) uint8 sRGB, row 0 at the top.

    The square, every region shaded (overlaps darker: the count a stencil buffer would hold), the
    shadow polygons dashed with their normals (red), the segments with theirs (blue), the light.
    `title` "" draws none; `font_px` sizes the labels (default: 8-point labels at 800 px).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Polygon, Rectangle

    L, s = as_light(light), as_segments(segments)
    if shadows is None:
        shadows = shadow_polygons(L, s)
    facing = classify(L, s)
    dpi = 100
    fig = Figure(figsize=(size_px / dpi, size_px / dpi), dpi=dpi)
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_axes([0.06, 0.05, 0.9, 0.9] if title == "" else [0.06, 0.06, 0.88, 0.88])
    pt = 8.0 * size_px / 800 if font_px is None else font_px * 72 / dpi
    ax.tick_params(labelsize=pt)
    ax.set_xlim(-0.03, 1.03)
    ax.set_ylim(-0.03, 1.03)
    ax.set_aspect("equal")
    ax.add_patch(Rectangle((0, 0), 1, 1, fill=False, lw=1.5, ec="black"))
    for sh in shadows:
        if sh.casts:
            ax.add_patch(Polygon(sh.region, closed=True, fc="0.2", alpha=0.28, ec="none"))
    arrow = dict(angles="xy", scale_units="xy", scale=1, width=0.004, headwidth=4,
                 headlength=5)
    for sh in shadows:
        for poly in sh.polygons:
            if poly.kind == "ray":
                ax.plot(*np.stack([poly.start, poly.end]).T, ls="--", lw=1.2, c="tab:red")
            mid = (poly.start + poly.end) / 2
            ax.quiver(*mid, *(poly.normal * normal_length), color="tab:red", **arrow)
    normals = outward_normals(s)
    for i, (seg, n) in enumerate(zip(s, normals)):
        style = "-" if facing[i] in (FRONT, BACK) else ":"
        ax.plot(*seg.T, ls=style, lw=3, c="tab:blue", solid_capstyle="round")
        mid = seg.mean(axis=0)
        ax.quiver(*mid, *(n * normal_length), color="tab:blue", **arrow)
        label = {FRONT: f"{i}", BACK: f"{i} back", EDGE_ON: f"{i} edge-on",
                 CONTAINS_LIGHT: f"{i} holds L"}[facing[i]]
        # Label beside the segment's first third, on the side opposite the normal, boxed, so
        # neither arrow (both sit at the midpoint) covers it.
        ax.annotate(label, seg[0] + (seg[1] - seg[0]) / 3 - n * 0.045, ha="center",
                    va="center", fontsize=pt, color="tab:blue", zorder=6,
                    bbox=dict(fc="white", ec="tab:blue", alpha=0.9, boxstyle="round,pad=0.2"))
    ax.plot(*L, marker="*", ms=2.2 * pt, mfc="gold", mec="darkorange")
    ax.annotate("L", L, xytext=(8, 6), textcoords="offset points", fontsize=1.4 * pt)
    if title != "":
        ax.set_title(title or "Shadow polygons in 2D: segments (blue) with outward normals, shadow "
                          "polygons (red) with normals\npointing out of the shadow; the darker "
                          "grey, the more shadow regions overlap (a stencil count)",
                     fontsize=9 * size_px / 800)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].copy()
