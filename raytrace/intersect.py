"""Ray intersections as the course teaches them, vectorised over rays.

A ray is  x(λ) = o + λ·r,  λ >= 0.  Every function takes `origins` (n, d) and `directions`
(n, d) float64 arrays (or anything that broadcasts to them) and returns λ for each ray, with
`np.inf` for a miss, so the nearest of several shapes is an `np.minimum`.  Directions need not be
unit length; λ is then measured in units of |r|.

Conventions shared by all shapes (the cases the course asks about):

* Hits behind the origin (λ <= t_min, default `T_MIN` = 0) are misses: a ray is a half-line.
* A ray parallel to a plane (r·n == 0, a grazing ray) misses it, even when it lies inside the
  plane: it meets the plane nowhere or everywhere, and neither is a point to shade.
* A ray that touches a sphere (discriminant exactly 0, a tangent, grazing ray) hits it, once.
* Triangles and parallelograms include their edges (barycentric / in-plane coordinates >= 0).
* Degenerate triangles (zero area) are missed.

All arithmetic is float64.
"""

from __future__ import annotations

import numpy as np

from .tolerances import T_MIN


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot product over the last axis: (..., d) . (..., d) -> (...)."""
    return np.einsum("...i,...i->...", a, b)


# ---------------------------------------------------------------------------------------------
# Plane (Hesse normal form) — in any dimension: in 2D the "plane" is a line
# ---------------------------------------------------------------------------------------------

def hesse(point, normal) -> tuple[np.ndarray, float]:
    """Hesse normal form n·x = d of the plane through `point` with normal `normal` (any length,
    non-zero): returns the unit normal n (d,) float64 and the distance d from the origin."""
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    return n, float(n @ np.asarray(point, dtype=np.float64))


def ray_plane(origins, directions, normal, distance, t_min: float = T_MIN) -> np.ndarray:
    """λ where each ray meets the plane n·x = d (Hesse normal form).

    origins, directions : (n, d) float64;  normal : (d,) or (n, d), unit length;  distance :
    float or (n,).  Returns λ : (n,) float64, np.inf for a miss (parallel ray, or hit at
    λ <= t_min, i.e. behind the origin).

        n·(o + λr) = d   =>   λ = (d − n·o) / (n·r)
    """
    o = np.asarray(origins, dtype=np.float64)
    r = np.asarray(directions, dtype=np.float64)
    n_dot_r = dot(normal, r)
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = (distance - dot(normal, o)) / n_dot_r
    return np.where((n_dot_r != 0.0) & (lam > t_min), lam, np.inf)


# ---------------------------------------------------------------------------------------------
# Sphere (in 2D: a circle)
# ---------------------------------------------------------------------------------------------

def ray_sphere(origins, directions, center, radius: float, t_min: float = T_MIN) -> np.ndarray:
    """Smallest λ > t_min where each ray meets the sphere |x − c| = R.

    origins, directions : (n, d) float64;  center : (d,);  radius : float > 0.
    Returns λ : (n,) float64, np.inf for a miss.

    |o + λr − c|² = R²  is the quadratic  a λ² + b λ + c' = 0  with
        a = r·r,   b = 2 r·(o − c),   c' = |o − c|² − R²,
    discriminant Δ = b² − 4ac':  Δ < 0 misses, Δ = 0 touches (grazing: one hit), Δ > 0 gives the
    roots λ1 <= λ2.  The hit is λ1 if λ1 > t_min (the ray starts outside, in front), else λ2 if
    λ2 > t_min (it starts inside), else none (the sphere is behind the ray).

    The roots are computed as q = −(b + sign(b)·√Δ)/2, λ = q/a and λ = c'/q: the same two roots as
    (−b ± √Δ)/2a, without the cancellation that formula suffers when |b| ≈ √Δ (a ray leaving
    a surface it has just hit, where c' ≈ 0).
    """
    o = np.asarray(origins, dtype=np.float64)
    r = np.asarray(directions, dtype=np.float64)
    oc = o - np.asarray(center, dtype=np.float64)
    a = dot(r, r)
    b = 2.0 * dot(r, oc)
    c = dot(oc, oc) - radius * radius
    disc = b * b - 4.0 * a * c
    hit = disc >= 0.0
    sq = np.sqrt(np.where(hit, disc, 0.0))
    q = -0.5 * (b + np.where(b >= 0.0, sq, -sq))
    with np.errstate(divide="ignore", invalid="ignore"):
        r1 = q / a
        r2 = np.where(q != 0.0, c / q, r1)  # q == 0 only when b == 0 and Δ == 0: a double root
    near, far = np.minimum(r1, r2), np.maximum(r1, r2)
    lam = np.where(near > t_min, near, np.where(far > t_min, far, np.inf))
    return np.where(hit, lam, np.inf)


# ---------------------------------------------------------------------------------------------
# Triangle and parallelogram: the plane first, then coordinates in the plane
# ---------------------------------------------------------------------------------------------

def plane_coordinates(p, corner, edge1, edge2) -> tuple[np.ndarray, np.ndarray]:
    """Coordinates (β, γ) of points p in the plane spanned from `corner` by edge1 and edge2:
    p − corner = β·edge1 + γ·edge2 (solved in the least-squares sense, exact for p in the plane).

    All arguments broadcast over leading axes, last axis 3.  Returns β, γ (...) float64; NaN
    where edge1 and edge2 are parallel (a degenerate triangle).

    With w = p − corner:  [e1·e1  e1·e2] [β]   [w·e1]
                          [e1·e2  e2·e2] [γ] = [w·e2]    (Cramer's rule below).
    """
    w = p - corner
    d11, d12, d22 = dot(edge1, edge1), dot(edge1, edge2), dot(edge2, edge2)
    w1, w2 = dot(w, edge1), dot(w, edge2)
    det = d11 * d22 - d12 * d12
    with np.errstate(divide="ignore", invalid="ignore"):
        beta = (d22 * w1 - d12 * w2) / det
        gamma = (d11 * w2 - d12 * w1) / det
    return beta, gamma


def _plane_hit(o, r, corner, edge1, edge2, t_min):
    """λ and the hit point of rays with the plane through corner spanned by edge1, edge2."""
    n = np.cross(edge1, edge2)
    n_dot_r = dot(n, r)
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = dot(n, corner - o) / n_dot_r  # = (d − n·o)/(n·r) with d = n·corner
    ok = (n_dot_r != 0.0) & (lam > t_min)
    lam = np.where(ok, lam, np.inf)
    p = o + np.where(ok, lam, 0.0)[..., None] * r
    return lam, p


def ray_triangle(origins, directions, a, b, c, t_min: float = T_MIN) -> np.ndarray:
    """λ where rays meet triangles (a, b, c), edges included.

    origins, directions : (..., 3);  a, b, c : (..., 3), broadcast against the rays, e.g.
    rays (n, 1, 3) against triangles (1, m, 3) give λ : (n, m).  Returns λ float64, np.inf for
    a miss.

    1. The ray meets the triangle's plane (normal n = (b − a) × (c − a)) at λ, point p.
    2. p = a + β(b − a) + γ(c − a) with barycentric coordinates (α, β, γ), α = 1 − β − γ;
       p is inside the triangle when α, β, γ >= 0.
    """
    o = np.asarray(origins, dtype=np.float64)
    r = np.asarray(directions, dtype=np.float64)
    e1, e2 = b - a, c - a
    lam, p = _plane_hit(o, r, a, e1, e2, t_min)
    beta, gamma = plane_coordinates(p, a, e1, e2)
    inside = (beta >= 0.0) & (gamma >= 0.0) & (beta + gamma <= 1.0)  # NaN compares False
    return np.where(inside, lam, np.inf)


def ray_parallelogram(origins, directions, corner, edge_u, edge_v,
                      t_min: float = T_MIN) -> np.ndarray:
    """λ where rays meet the parallelogram corner + s·edge_u + t·edge_v, s, t in [0, 1] (the
    scene's finite planes), edges included.  Shapes as in `ray_triangle`."""
    o = np.asarray(origins, dtype=np.float64)
    r = np.asarray(directions, dtype=np.float64)
    lam, p = _plane_hit(o, r, corner, edge_u, edge_v, t_min)
    s, t = plane_coordinates(p, corner, edge_u, edge_v)
    inside = (s >= 0.0) & (s <= 1.0) & (t >= 0.0) & (t <= 1.0)
    return np.where(inside, lam, np.inf)


# ---------------------------------------------------------------------------------------------
# Directions leaving a surface
# ---------------------------------------------------------------------------------------------

def reflect(directions, normals) -> np.ndarray:
    """Ideal mirror reflection r − 2(n·r)n of directions (n, 3) about unit normals (n, 3)."""
    return directions - 2.0 * dot(normals, directions)[..., None] * normals


def refract(directions, normals, eta) -> tuple[np.ndarray, np.ndarray]:
    """Snell's law: n1 sin θ1 = n2 sin θ2.

    directions : (n, 3) unit;  normals : (n, 3) unit, facing the incoming ray (n·r < 0);
    eta : (n,) or float, n1 / n2 (the side the ray comes from over the side it enters).
    Returns the refracted directions (n, 3), unit, and `tir` (n,) bool: total internal
    reflection (sin θ2 would exceed 1), where the returned direction is the mirror reflection.

        cos θ1 = −n·r,   k = 1 − η² (1 − cos² θ1) = cos² θ2,   t = η r + (η cos θ1 − √k) n
    """
    eta = np.asarray(eta, dtype=np.float64)
    cos1 = -dot(normals, directions)
    k = 1.0 - eta * eta * (1.0 - cos1 * cos1)
    tir = k < 0.0
    eta_c = eta[..., None] if eta.ndim else eta
    t = eta_c * directions + (eta * cos1 - np.sqrt(np.where(tir, 0.0, k)))[..., None] * normals
    return np.where(tir[..., None], reflect(directions, normals), t), tir
