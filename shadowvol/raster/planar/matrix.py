"""Planar projected shadows (Blinn 1988, "Me and my (fake) shadow"): the projection matrix.

A receiving plane is P = (n, d): the points x with n . x + d = 0.  A light is a homogeneous point
L = (l, w): a point light at position l is (l, 1); a directional light is the point at infinity it
comes FROM, so for a light travelling along t (this project's convention, see
`shadowvol.scene.DirectionalLight`) it is (-t, 0).  The matrix

    M = (P . L) I - L P^T                                   (4 x 4)

maps a homogeneous point X to M X = (P . L) X - (P . X) L, a combination of X and L (so the image
lies on the line through the light and X) with P . (M X) = (P . L)(P . X) - (P . X)(P . L) = 0
(so it lies on the plane).  A point already on the plane (P . X = 0) maps to (P . L) X: itself.
For a directional light the image is x - t (n . x + d) / (n . t): x moved along t onto the plane.

This module returns M multiplied by the sign of P . L, the same projective map, so that the w of
every real shadow point comes out positive: GL clips w < 0, and with the light on the negative
side of the plane (P . L < 0) the unsigned formula would give every shadow point a negative w.

Drawbacks, which the course's demo puts beside shadow volumes to make them plain to see:
- Only planar receivers: one matrix per plane, and the shadow falls on the infinite plane, so it
  must be clipped to the receiver's extent (with the stencil: draw shadows only where the receiver
  wrote its reference value) or it hangs in the air past the floor's edge.
- No shadows on other objects and no self-shadowing: the occluders are squashed onto the plane, so
  a box cannot shadow the sphere beside it, nor a torus its own inside.  Shadow volumes do both.
- Anti-shadows: a point behind the light, or on the far side of the plane, still projects onto the
  plane (through the light, or "upward" from below the floor) and draws a false shadow.  Each
  point must pass `casts_shadow` (0 <= (P . X) / (P . L) < 1 for a point light: between the light
  and the plane), or the occluder must be clipped against the plane through the light parallel to
  the receiver.
- Double blending: the projected triangles overlap (front and back of a closed mesh both project),
  so drawing them with a blended dark colour darkens overlaps twice.  The fix is the stencil:
  draw each shadow pixel once (stencil test "equal to the receiver's value", then zero it).
- Z-fighting with the receiver: the flattened geometry is coplanar with it; polygon offset or
  drawing with the depth test off inside the stencil-marked receiver avoids it.
- The projected geometry is redrawn every frame the light or objects move: cheap for a floor,
  useless for a room of receivers.
"""

from __future__ import annotations

import numpy as np

from shadowvol.scene import DirectionalLight, PointLight, SpotLight

# |P . L| (for a unit plane normal: the light's distance from the plane, or |cos| between the
# travel direction and the normal for a directional light) below which the projection is
# degenerate: a point light in the plane, or a directional light grazing it.
DEGENERATE_TOLERANCE = 1e-9


def plane_equation(plane_point, plane_normal) -> np.ndarray:
    """(4,) float64 P = (n, d) with n the unit normal and d = -n . plane_point."""
    n = np.asarray(plane_normal, dtype=np.float64)
    length = np.linalg.norm(n)
    if n.shape != (3,) or not np.isfinite(length) or length == 0.0:
        raise ValueError(f"plane_normal must be a non-zero 3-vector, got {plane_normal!r}")
    n = n / length
    return np.append(n, -float(n @ np.asarray(plane_point, dtype=np.float64)))


def homogeneous_light(light) -> np.ndarray:
    """(4,) float64 homogeneous position of a light.

    light : a PointLight or SpotLight (-> (position, 1)), a DirectionalLight (-> (-direction, 0):
            the point at infinity the light comes from), or a 4-vector taken as it is.
    """
    if isinstance(light, (PointLight, SpotLight, DirectionalLight)):
        return light.homogeneous
    L = np.asarray(light, dtype=np.float64)
    if L.shape != (4,) or not np.isfinite(L).all() or not L.any():
        raise ValueError(f"a homogeneous light is 4 finite numbers, not all zero; got {light!r}")
    return L


def projection_matrix(plane_point, plane_normal, light) -> np.ndarray:
    """(4, 4) float64 M projecting points from `light` onto the plane.

    plane_point  : (3,) a point of the receiving plane
    plane_normal : (3,) its normal (any length; the side it points to is the "lit" side only
                   through the sign of P . L, which M is normalised by)
    light        : see `homogeneous_light`; (Lx, Ly, Lz, 1) for a point, (dx, dy, dz, 0) for the
                   direction the light comes FROM (i.e. minus a DirectionalLight's `direction`)

    Use with column vectors: X' = M @ (x, y, z, 1), then divide by X'[3] (or hand M to GL as the
    model matrix of the shadow pass, after the object's own model matrix).  Raises ValueError
    when the light lies in the plane (point) or travels parallel to it (directional).
    """
    P = plane_equation(plane_point, plane_normal)
    L = homogeneous_light(light)
    pl = float(P @ L)
    scale = np.linalg.norm(L[:3]) if L[3] == 0 else abs(L[3])
    if abs(pl) <= DEGENERATE_TOLERANCE * scale:
        what = "travels parallel to" if L[3] == 0 else "lies in"
        raise ValueError(f"the light {what} the receiving plane: the projection is degenerate")
    M = pl * np.eye(4) - np.outer(L, P)
    return np.sign(pl) * M


def project_points(matrix, points) -> np.ndarray:
    """(n, 3) float64 points -> (n, 3) float64 projected points (after the divide by w)."""
    p = np.asarray(points, dtype=np.float64)
    h = np.concatenate([p, np.ones((len(p), 1))], axis=1) @ np.asarray(matrix).T
    return h[:, :3] / h[:, 3:]


def casts_shadow(plane_point, plane_normal, light, points) -> np.ndarray:
    """(n,) bool: which points make a real shadow rather than an anti-shadow.

    With s = (P . X) / (P . L): a point light's shadow is real for 0 <= s < 1 (the point lies
    between the light and the plane, or on the plane); a directional light's for s >= 0 (the point
    is on the side the light comes from).  Points with s < 0 are below the plane; with s >= 1 they
    are level with or beyond the light and project through it (the anti-shadow).
    """
    P = plane_equation(plane_point, plane_normal)
    L = homogeneous_light(light)
    if L[3] != 0:
        L = L / L[3]            # s compares distances: the light's w must be 1
    p = np.asarray(points, dtype=np.float64)
    s = (p @ P[:3] + P[3]) / float(P @ L)
    ok = s >= 0
    if L[3] != 0:
        ok &= s < 1
    return ok
