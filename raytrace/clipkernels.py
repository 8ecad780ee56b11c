"""A pixel's outline cut to a box about the light, in numba (`raytrace.windingkernels`).

The union is only measured inside the light, so its outline matters only there: the edges are
cut to a box B a little larger than the light (Liang and Barsky), and the cycle is closed
again along B's sides, each stretch between two points where the outline crosses them
counted as many times as the outline winds just inside it (counter-clockwise about B).  The
winding numbers inside B are those of the whole outline and 0 outside, so the union's
boundary inside B, and its measures over the light, are the same; the outline's edges and
crossings outside B (most of them on a dense mesh: the rim of the triangles that reach into
the pyramid lies around the light) are left out of the noding.

The winding just inside B at its first corner is counted along a ray in +x from that corner
(as `coverkernels.covers` counts), and the count is carried around B, adding each crossing
edge's count where it turns left across B's side.  Any doubt (a corner of the outline, or a
corner of B, within `windings.DOUBT` of the other's edges or sides; two crossings at one
point; a count that does not close) and the pixel is not cut: the caller keeps its whole
outline.
"""

from __future__ import annotations

import numpy as np

from .outlinekernels import _level, _turn
from .packetkernels import _jit


@_jit()
def clipped(ax, ay, bx, by, ia, ib, cnt, box, big, margin, wind):
    """The outline a -> b (m,) with corner ids ia, ib (< big) and counts cnt (m,) (those of
    its edges whose boxes meet the box, at least) cut to the box (x0, y0, x1, y1) and closed
    along its sides, wind: the whole outline's winding at the box's first corner (`survey`):
    (certain, ax, ay, bx, by, ia, ib, cnt, where B's stretches start), the cut edges (the
    same floats where whole) and then B's stretches (counter-clockwise: outside B on their
    right); new corners' ids from big on (B's corners big .. big + 3)."""
    x0, y0, x1, y1 = box[0], box[1], box[2], box[3]
    w, h = x1 - x0, y1 - y0
    m = ax.shape[0]
    ok = _apart(ax, ay, bx, by, box, margin)
    size = 3 * m + 8
    oax, oay, obx, oby = np.empty(size), np.empty(size), np.empty(size), np.empty(size)
    oia, oib, ocnt = np.empty(size, np.int64), np.empty(size, np.int64), np.empty(size, np.int64)
    # the points along B's outline: corners, then crossings (place s, x, y, id, change)
    place, px, py = np.empty(2 * m + 4), np.empty(2 * m + 4), np.empty(2 * m + 4)
    pid, change = np.empty(2 * m + 4, np.int64), np.zeros(2 * m + 4, np.int64)
    for k in range(4):
        place[k] = (0.0, w, w + h, 2 * w + h)[k]
        px[k], py[k] = (x0, x1, x1, x0)[k], (y0, y0, y1, y1)[k]
        pid[k] = big + k
    g, n_pts = 0, 4
    for e in range(m):
        if not ok:
            break
        dx, dy = bx[e] - ax[e], by[e] - ay[e]
        inside, t0, t1, s0, s1 = _span(ax[e], ay[e], dx, dy, box)
        if not inside or not t0 < t1:
            continue
        sx, sy, tx, ty, sa, sb = ax[e], ay[e], bx[e], by[e], ia[e], ib[e]
        for end in range(2):
            side, t = (s0, t0) if end == 0 else (s1, t1)
            if side < 0:
                continue
            x, y = _on_side(side, ax[e] + t * dx, ay[e] + t * dy, box)
            place[n_pts] = _place(side, x, y, box)
            px[n_pts], py[n_pts], pid[n_pts] = x, y, big + n_pts
            # + where the edge turns left across B's side (counter-clockwise along it)
            tx_, ty_ = ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))[side]
            change[n_pts] = cnt[e] if dx * ty_ - dy * tx_ > 0 else -cnt[e]
            if end == 0:
                sx, sy, sa = x, y, big + n_pts
            else:
                tx, ty, sb = x, y, big + n_pts
            n_pts += 1
        oax[g], oay[g], obx[g], oby[g], oia[g], oib[g], ocnt[g] = sx, sy, tx, ty, sa, sb, cnt[e]
        g += 1
    if not ok:
        return False, oax[:0], oay[:0], obx[:0], oby[:0], oia[:0], oib[:0], ocnt[:0], 0
    order = np.argsort(place[:n_pts], kind="mergesort")
    for k in range(1, n_pts):                            # no two points at one place
        ok &= place[order[k]] - place[order[k - 1]] > margin * (w + h)
    at, cut = wind, g
    for k in range(n_pts):                               # B's stretches, counted
        i, j = order[k], order[(k + 1) % n_pts]
        at += change[i]
        ok &= at >= 0
        if at > 0:
            oax[g], oay[g], obx[g], oby[g] = px[i], py[i], px[j], py[j]
            oia[g], oib[g], ocnt[g] = pid[i], pid[j], at
            g += 1
    ok &= at == wind
    return ok, oax[:g], oay[:g], obx[:g], oby[:g], oia[:g], oib[:g], ocnt[:g], cut


@_jit()
def survey(uncut, r0, r1, rims, e0, e1, box, margin):
    """The shadows uncut[r0:r1] (3, 2) each and the rims' edges e0..e1 (`rims`: flat (e, 2,
    2), ids, count) against the box: (whether some edge's box meets it, whether the winding
    number at its first corner is certain, that winding) by a ray in +x (the sum of each
    triangle's and each edge's crossings: the same as the outline's, whose cancelled edges
    cross it as often each way)."""
    rim, _, count = rims
    x0, y0, x1, y1 = box[0], box[1], box[2], box[3]
    meets, wind, ok = False, 0, True
    for r in range(r0, r1):
        meets |= not (min(uncut[r, 0, 0], min(uncut[r, 1, 0], uncut[r, 2, 0])) > x1
                      or max(uncut[r, 0, 0], max(uncut[r, 1, 0], uncut[r, 2, 0])) < x0
                      or min(uncut[r, 0, 1], min(uncut[r, 1, 1], uncut[r, 2, 1])) > y1
                      or max(uncut[r, 0, 1], max(uncut[r, 1, 1], uncut[r, 2, 1])) < y0)
        signed = (uncut[r, 1, 0] - uncut[r, 0, 0]) * (uncut[r, 2, 1] - uncut[r, 0, 1]) - \
            (uncut[r, 1, 1] - uncut[r, 0, 1]) * (uncut[r, 2, 0] - uncut[r, 0, 0])
        if signed == 0:
            continue
        for k in range(3):
            a, b = (k, (k + 1) % 3) if signed > 0 else ((k + 1) % 3, k)
            sure, w = _crossed(uncut[r, a, 0], uncut[r, a, 1], uncut[r, b, 0], uncut[r, b, 1],
                               x0, y0, margin)
            ok &= sure
            wind += w
    for g in range(e0, e1):
        meets |= not (min(rim[g, 0, 0], rim[g, 1, 0]) > x1 or max(rim[g, 0, 0], rim[g, 1, 0]) < x0
                      or min(rim[g, 0, 1], rim[g, 1, 1]) > y1
                      or max(rim[g, 0, 1], rim[g, 1, 1]) < y0)
        sure, w = _crossed(rim[g, 0, 0], rim[g, 0, 1], rim[g, 1, 0], rim[g, 1, 1], x0, y0,
                           margin)
        ok &= sure
        wind += w * count[g]
    return meets, ok, wind


@_jit(inline="always")
def _crossed(ax, ay, bx, by, x, y, margin):
    """(certain, +1, -1 or 0): the edge a -> b crosses the ray in +x from x, y going up, going
    down, or not (`coverkernels.covers`'s rule)."""
    up, down = _level(ay, by, y)
    if not (up or down):
        return True, 0
    ux, uy = bx - ax, by - ay
    side, sure = _turn(ux, uy, x - ax, y - ay, abs(ux) + abs(uy), margin)
    if up and side > 0:
        return sure, 1
    if down and side < 0:
        return sure, -1
    return sure, 0


@_jit(inline="always")
def _span(x, y, dx, dy, box):
    """Liang and Barsky: the part t0..t1 of the segment from x, y along dx, dy inside the box,
    and the sides (0 bottom, 1 right, 2 top, 3 left; -1 none) it enters and leaves by:
    (whether any of it is, t0, t1, s0, s1)."""
    t0, t1, s0, s1 = 0.0, 1.0, -1, -1
    inside = True
    for k in range(4):                   # B's sides: bottom, right, top, left (counter-clockwise)
        p = (-dy, dx, dy, -dx)[k]
        q = (y - box[1], box[2] - x, box[3] - y, x - box[0])[k]
        if p == 0:
            inside &= q >= 0
            continue
        r = q / p
        if p < 0 and r > t0:
            t0, s0 = r, k
        elif p > 0 and r < t1:
            t1, s1 = r, k
    return inside, t0, t1, s0, s1


@_jit(inline="always")
def _on_side(side, x, y, box):
    """The point x, y put on B's side (0 bottom, 1 right, 2 top, 3 left) exactly."""
    if side == 0:
        return x, box[1]
    if side == 1:
        return box[2], y
    if side == 2:
        return x, box[3]
    return box[0], y


@_jit(inline="always")
def _place(side, x, y, box):
    """Where x, y on B's side lies along B's outline, counter-clockwise from its first
    corner."""
    w, h = box[2] - box[0], box[3] - box[1]
    if side == 0:
        return x - box[0]
    if side == 1:
        return w + (y - box[1])
    if side == 2:
        return w + h + (box[2] - x)
    return 2 * w + h + (box[3] - y)


@_jit()
def _apart(ax, ay, bx, by, box, margin):
    """Whether no corner of the outline lies within margin of B's sides (of B's size) and no
    corner of B within margin of an edge (`_turn`'s doubt) whose box holds it."""
    x0, y0, x1, y1 = box[0], box[1], box[2], box[3]
    tol = margin * ((x1 - x0) + (y1 - y0))
    for e in range(ax.shape[0]):
        for x, y in ((ax[e], ay[e]), (bx[e], by[e])):
            near_x = (abs(x - x0) <= tol or abs(x - x1) <= tol) and y0 - tol <= y <= y1 + tol
            near_y = (abs(y - y0) <= tol or abs(y - y1) <= tol) and x0 - tol <= x <= x1 + tol
            if near_x or near_y:
                return False
        ux, uy = bx[e] - ax[e], by[e] - ay[e]
        for k in range(4):
            cx, cy = (x0, x1, x1, x0)[k], (y0, y0, y1, y1)[k]
            if min(ax[e], bx[e]) <= cx <= max(ax[e], bx[e]) and \
                    min(ay[e], by[e]) <= cy <= max(ay[e], by[e]):
                _, sure = _turn(ux, uy, cx - ax[e], cy - ay[e], abs(ux) + abs(uy), margin)
                if not sure:
                    return False
    return True
