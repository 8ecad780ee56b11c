"""The in-plane axes of a plane given by its normal: the ground that the `plane` primitive
(`shadowvol.primitives`) and the rect and disk area lights (`shadowvol.lights`) share, so a
plane and a light of the same normal lay their u, v the same way."""

from __future__ import annotations

import numpy as np


def default_plane_axes(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """In-plane unit axes (u, v) with u x v = normal: u is world x projected onto the plane
    (world z projected where |normal.x| >= 0.9: x's projection would be short there)."""
    ref = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    u = ref - normal * float(ref @ normal)
    u = u / np.linalg.norm(u)
    return u, np.cross(normal, u)
