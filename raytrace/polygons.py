"""Plane geometry of the exact visible part of an area light, float64, vectorised (numpy).

* `clip`: convex polygons (n, k, 3) cut by one plane each (Sutherland-Hodgman, all at once).
* `project`: points seen from p, carried onto the light's plane, in its (u, v) coordinates.
* `ring_measures`: per closed ring of a polygon in the light's plane, its area and Lambert's
  irradiance at p (unit radiance): E = 1/2 sum_i theta_i n . unit(x_i x x_(i+1)), x_i the
  corners seen from p (Arvo 1995), exact for a ring on the closed side of p's tangent plane
  that the normal n points into.
* `disk_ring_measures`: the same for the part of a disk inside a ring: the ring's edges inside
  the disk are straight pieces, the disk's boundary inside the ring arcs, each arc's Lambert
  integral in closed form (below), so the disk minus polygons is exact too.

Both measures are integrals over the boundary, 1/2 closed-integral of (x x dx) . n / |x|^2 and
of (P x dP) / 2: additive over pieces of it, so a region with holes is its outer rings less
its holes, and an edge shared by two rings with opposite orientations cancels.
"""

from __future__ import annotations

import importlib

import numpy as np


def clip(points: np.ndarray, counts: np.ndarray, dist: np.ndarray
         ) -> tuple[np.ndarray, np.ndarray]:
    """Convex polygons cut to where `dist` >= 0.

    points : (n, k, d) float64, polygon i is points[i, :counts[i]] (in order), d = 2 or 3
    dist : (n, k) float64, the signed distance of each corner from polygon i's plane
    Returns (points (n, k', 3), counts (n,)): the kept part of each, k' <= k + 1 (0 corners
    where nothing is kept).  A crossing edge's new corner is its float64 interpolation."""
    n, k, dim = points.shape
    at = np.arange(k)[None]
    valid = at < counts[:, None]
    after = (at + 1) % np.maximum(counts[:, None], 1)
    d1 = np.take_along_axis(dist, after, 1)
    p1 = np.take_along_axis(points, after[..., None], 1)
    inside, inside1 = dist >= 0, d1 >= 0
    keep = valid & inside
    cross = valid & (inside != inside1)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(cross, dist / np.where(cross, dist - d1, 1.0), 0.0)
    meet = points + t[..., None] * (p1 - points)
    slots = np.stack([points, meet], axis=2).reshape(n, 2 * k, dim)
    ok = np.stack([keep, cross], axis=2).reshape(n, 2 * k)
    new = ok.sum(axis=1)
    width = max(int(new.max(initial=0)), 1)
    order = np.argsort(~ok, axis=1, kind="stable")[:, :width]
    return np.take_along_axis(slots, order[..., None], 1), new


def project(points: np.ndarray, eye: np.ndarray, center: np.ndarray, normal: np.ndarray,
            axes: np.ndarray) -> np.ndarray:
    """(n, k, 2): points (n, k, 3) seen from eye (n, 3), carried along the line from the eye
    to the plane through `center` with unit `normal`, in that plane's coordinates
    (axes (2, 3), rows u, v).  Each point must lie strictly between the eye's parallel plane
    and beyond-or-on the light's (the cut pyramid guarantees it)."""
    ray = points - eye[:, None]
    rel = eye - center
    height = dot(rel, normal)                            # (n,), > 0: the emitting side
    with np.errstate(divide="ignore", invalid="ignore"):  # unused slots past a polygon's count
        scale = height[:, None] / -dot(ray, normal)       # (n, k)
        return np.stack([dot(rel, axis)[:, None] + scale * dot(ray, axis) for axis in axes],
                        axis=-1)


def kernels(name: str = "exactkernels"):
    """`raytrace.exactkernels` (the exact visibility's numba loops, the `fast` extra; or
    another module of them by name, `raytrace.windingkernels`), or None where numba is
    missing (or a test has set its sys.modules entry to None)."""
    try:
        return importlib.import_module(f"{__package__}.{name}")
    except ImportError:
        return None


def dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """u . v over the last axis (3), as three products summed left to right (numba's kernels,
    `raytrace.exactkernels`, sum them alike: the same bits; matmul and einsum may not)."""
    return u[..., 0] * v[..., 0] + u[..., 1] * v[..., 1] + u[..., 2] * v[..., 2]


def _edges(coords: np.ndarray, ring: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Consecutive corners of closed rings (the last corner repeats the first, as GEOS writes
    them): starts (e, 2), ends (e, 2) and each edge's ring (e,)."""
    same = ring[1:] == ring[:-1]
    return coords[:-1][same], coords[1:][same], ring[:-1][same]


def ring_measures(coords: np.ndarray, ring: np.ndarray, rings: int, eye: np.ndarray,
                  normal: np.ndarray, center: np.ndarray, axes: np.ndarray,
                  direct: bool = False) -> tuple[np.ndarray, ...]:
    """Per ring (rings,): |area| and |Lambert's irradiance| at its eye, unit radiance; with
    `direct` also the unattenuated measure (`direct_measure`).

    coords : (c, 2) closed rings in the light's plane coordinates, ring (c,) their ring index;
    eye, normal : (rings, 3) each ring's receiving point and its unit normal; center (3,),
    axes (2, 3) the light's plane."""
    a, b, r = _edges(coords, ring)
    area = np.bincount(r, (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]) / 2, rings)
    x0 = center + a @ axes - eye[r]
    x1 = center + b @ axes - eye[r]
    lam = _edge_lambert(x0, x1, normal[r])
    out = (np.abs(area), np.abs(np.bincount(r, lam, rings)))
    if direct:
        out += (direct_measure(*_segments(a, b, r, eye, center, axes), rings, eye, normal,
                               center, axes),)
    return out


# Gauss-Legendre nodes and weights on [-1, 1] for the boundary integrals of `direct_measure`.
GAUSS_NODES, GAUSS_WEIGHTS = np.polynomial.legendre.leggauss(16)
# Pieces a boundary curve is cut into at most (each no longer than the eye's height over the
# light's plane, below this many).
MAX_PIECES = 512


def _pieces(length: np.ndarray, height: np.ndarray) -> np.ndarray:
    """(e,) pieces per curve of `length` (e,) seen from `height` (e,) over the plane: each
    piece no longer than the height (then the integrands' nearest complex singularity is at
    least a piece's length off it and 16 Gauss points give ~1e-16 of it)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        m = np.ceil(length / np.abs(height))
    return np.clip(np.nan_to_num(m, nan=1.0, posinf=MAX_PIECES), 1, MAX_PIECES).astype(np.int64)


def _nodes(m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For curves cut into m (e,) pieces: per node, its curve (k,), its parameter in [0, 1]
    (k,) and its weight (k,) (summing to 1 over a curve)."""
    curve = np.repeat(np.arange(len(m)), m)
    piece = np.arange(len(curve)) - np.repeat(np.cumsum(m) - m, m)
    per = m[curve][:, None]
    t = (piece[:, None] + (GAUSS_NODES[None] + 1) / 2) / per
    w = np.broadcast_to(GAUSS_WEIGHTS[None] / 2, t.shape) / per
    return np.repeat(curve, len(GAUSS_NODES)), t.reshape(-1), w.reshape(-1)


def _height(eye: np.ndarray, center: np.ndarray, axes: np.ndarray) -> np.ndarray:
    return (eye - center) @ np.cross(axes[0], axes[1])


def _segments(a: np.ndarray, b: np.ndarray, r: np.ndarray, eye: np.ndarray,
              center: np.ndarray, axes: np.ndarray):
    """Quadrature nodes of the straight edges a -> b (e, 2) of rings r (e,): points (k, 2),
    derivatives times weights (k, 2), ring (k,)."""
    d = b - a
    m = _pieces(np.linalg.norm(d, axis=1), _height(eye[r], center, axes))
    e, t, w = _nodes(m)
    return a[e] + t[:, None] * d[e], d[e] * w[:, None], r[e]


def _arc_nodes(radius: float, start: np.ndarray, sweep: np.ndarray, r: np.ndarray,
               eye: np.ndarray, center: np.ndarray, axes: np.ndarray):
    """Quadrature nodes of the arcs of the circle about the plane's origin from angle `start`
    through `sweep` (e,): as `_segments`."""
    m = _pieces(radius * np.abs(sweep), _height(eye[r], center, axes))
    e, t, w = _nodes(m)
    phi = start[e] + t * sweep[e]
    y = radius * np.stack([np.cos(phi), np.sin(phi)], axis=1)
    dy = radius * np.stack([-np.sin(phi), np.cos(phi)], axis=1) * (sweep[e] * w)[:, None]
    return y, dy, r[e]


def direct_measure(y: np.ndarray, dy: np.ndarray, r: np.ndarray, rings: int, eye: np.ndarray,
                   normal: np.ndarray, center: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """Per ring (rings,): |integral over its inside of cos(at the eye) cos(at the light) dA|,
    the light's cosine-weighted measure without the inverse-square fall-off (the limit of the
    renderers' sampled area light, docs/CONVENTIONS.md), from quadrature nodes of the ring's
    boundary: points y (k, 2) in the plane's coordinates, dy (k, 2) their derivative times
    weight, r (k,) their ring.

    With q the eye's foot and h its height over the plane, z = y - q, t = |z|^2:
    cos cos = |h| (c + a . z) / (t + h^2) (a, c: the eye's normal in the plane's terms), and
    by the divergence theorem (nu ds = (dy_v, -dy_u), outward for a counter-clockwise ring)
      int a . z / (t + h^2) dA = oint 1/2 ln(t + h^2) a . nu ds,
      int 1 / (t + h^2) dA    = oint z . nu ln(1 + t / h^2) / (2 t) ds.
    The integrands are smooth (h != 0); Gauss-Legendre on pieces no longer than |h|."""
    e_eye, e_normal = eye[r], normal[r]
    w = center - e_eye                                     # (k, 3)
    h = w @ np.cross(axes[0], axes[1])
    q = -(w @ axes.T)
    a = e_normal @ axes.T                                  # (k, 2)
    c = (e_normal * w).sum(axis=1) + (a * q).sum(axis=1)
    z = y - q
    t = (z * z).sum(axis=1)
    nu = np.stack([dy[:, 1], -dy[:, 0]], axis=1)
    h2 = h * h
    term = (0.5 * np.log(t + h2) * (a * nu).sum(axis=1)
            + c * (z * nu).sum(axis=1) * _log1pc(t / h2) / (2 * h2))
    return np.abs(np.bincount(r, np.abs(h) * term, rings))


def _edge_lambert(x0: np.ndarray, x1: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """(e,): 1/2 theta n . unit(x0 x x1), the Lambert term of the straight edges x0 -> x1 seen
    from the origin (0 for an edge of no length)."""
    cross = np.cross(x0, x1)
    sine = np.linalg.norm(cross, axis=1)
    theta = np.arctan2(sine, (x0 * x1).sum(axis=1))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(sine > 0, 0.5 * theta * (cross * normal).sum(axis=1) / sine, 0.0)


def disk_ring_measures(coords: np.ndarray, ring: np.ndarray, rings: int, radius: float,
                       eye: np.ndarray, normal: np.ndarray, center: np.ndarray,
                       axes: np.ndarray, direct: bool = False) -> tuple[np.ndarray, ...]:
    """Per ring (rings,): the area of the disk (centre `center`, the origin of the plane's
    coordinates, `radius`) inside the ring and Lambert's irradiance from that part, both
    >= 0, and with `direct` the unattenuated measure (`direct_measure`); arguments as
    `ring_measures`.

    Each edge a -> b is cut where it crosses the circle: its part inside is a straight piece,
    each part outside is replaced by the circle's arc between the same rays from the centre
    (the ring's triangle fan from the centre, cut to the disk: the fan's radial sides cancel)."""
    a, b, r = _edges(coords, ring)
    d = b - a
    qa = (d * d).sum(axis=1)
    qb = (a * d).sum(axis=1)
    qc = (a * a).sum(axis=1) - radius * radius
    disc = qb * qb - qa * qc
    root = np.sqrt(np.maximum(disc, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = np.clip((-qb - root) / qa, 0.0, 1.0)
        t1 = np.clip((-qb + root) / qa, 0.0, 1.0)
    meets = (disc > 0) & (qa > 0) & (t0 < t1)
    t0, t1 = np.where(meets, t0, 1.0), np.where(meets, t1, 1.0)
    p0, p1 = a + t0[:, None] * d, a + t1[:, None] * d
    # straight: p0 -> p1 (no length where the edge misses); arcs: a -> p0 and p1 -> b
    area = (p0[:, 0] * p1[:, 1] - p0[:, 1] * p1[:, 0]) / 2
    e_eye, e_normal = eye[r], normal[r]
    lam = _edge_lambert(center + p0 @ axes - e_eye, center + p1 @ axes - e_eye, e_normal)
    arcs = _Arcs(radius, center - e_eye, e_normal, axes)
    nodes = [_segments(p0, p1, r, eye, center, axes)] if direct else []
    for start, end in ((a, p0), (p1, b)):
        sweep = np.arctan2(start[:, 0] * end[:, 1] - start[:, 1] * end[:, 0],
                           (start * end).sum(axis=1))
        area = area + radius * radius * sweep / 2
        angle = np.arctan2(start[:, 1], start[:, 0])
        lam = lam + arcs.integral(angle, sweep)
        if direct:
            nodes.append(_arc_nodes(radius, angle, sweep, r, eye, center, axes))
    out = (np.abs(np.bincount(r, area, rings)), np.abs(np.bincount(r, lam, rings)))
    if direct:
        y, dy, k = (np.concatenate(part) for part in zip(*nodes))
        out += (direct_measure(y, dy, k, rings, eye, normal, center, axes),)
    return out


class _Arcs:
    """Lambert's term 1/2 integral of n . (x x dx) / |x|^2 along arcs of the circle
    x(phi) = c + R (cos phi u + sin phi v) seen from the origin (c : (e, 3) the disk's centre
    seen from each edge's eye), in closed form.

    |x|^2 = A + rho cos(phi - phi0) with A = |c|^2 + R^2, rho = 2 R |c_uv| (> A never: A - rho
    = (|c_uv| - R)^2 + (c . n_L)^2 > 0 off the light's plane), and n . (x x dx/dphi) =
    alpha + beta cos phi + gamma sin phi.  With psi = phi - phi0 and s = sqrt(A^2 - rho^2):
      int dpsi / (A + rho cos psi)      = (psi - 2 atan(rho sin psi / (A + s + rho cos psi))) / s
      int cos psi / (A + rho cos psi)   = (psi - A int dpsi / (...)) / rho
      int sin psi / (A + rho cos psi)   = -ln(A + rho cos psi) / rho,
    the last two written without dividing small differences by a small rho (`_atanc`,
    `_log1pc`)."""

    def __init__(self, radius: float, c: np.ndarray, normal: np.ndarray, axes: np.ndarray):
        u, v = axes
        cu, cv = c @ u, c @ v
        self.big = (c * c).sum(axis=1) + radius * radius
        in_plane = np.hypot(cu, cv)
        self.rho = 2 * radius * in_plane
        light_normal = np.cross(u, v)
        gap = (in_plane - radius) ** 2 + (c @ light_normal) ** 2       # A - rho
        self.s = np.sqrt(gap * (self.big + self.rho))
        self.phi0 = np.arctan2(cv, cu)
        alpha = radius * radius * (normal @ light_normal)
        beta = radius * (np.cross(c, v) * normal).sum(axis=1)
        gamma = -radius * (np.cross(c, u) * normal).sum(axis=1)
        cos0, sin0 = np.cos(self.phi0), np.sin(self.phi0)
        self.alpha = alpha
        self.beta = beta * cos0 + gamma * sin0
        self.gamma = -beta * sin0 + gamma * cos0

    def integral(self, start: np.ndarray, sweep: np.ndarray) -> np.ndarray:
        """(e,): the term over the arc from angle `start` through `sweep` (signed) radians."""
        A, rho, s = self.big, self.rho, self.s
        psi1 = start - self.phi0
        psi2 = psi1 + sweep
        den1, den2 = A + s + rho * np.cos(psi1), A + s + rho * np.cos(psi2)
        # atan(rho sin psi / den) / rho, exact as rho -> 0
        at1 = np.sin(psi1) / den1 * _atanc(rho * np.sin(psi1) / den1)
        at2 = np.sin(psi2) / den2 * _atanc(rho * np.sin(psi2) / den2)
        i0 = (sweep - 2 * rho * (at2 - at1)) / s
        i1 = -sweep * rho / (s * (A + s)) + 2 * A / s * (at2 - at1)
        first = A + rho * np.cos(psi1)
        change = (np.cos(psi2) - np.cos(psi1)) / first
        i2 = -change * _log1pc(rho * change)
        return 0.5 * (self.alpha * i0 + self.beta * i1 + self.gamma * i2)


def _atanc(y: np.ndarray) -> np.ndarray:
    """atan(y) / y, 1 at 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.abs(y) > 1e-8, np.arctan(y) / y, 1.0 - y * y / 3)


def _log1pc(z: np.ndarray) -> np.ndarray:
    """log1p(z) / z, 1 at 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.abs(z) > 1e-8, np.log1p(z) / z, 1.0 - z / 2)
