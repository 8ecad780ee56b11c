"""Choosing z-pass or z-fail per caster: the near-clip volume test (Lengyel 2002, as in Doom 3's
and OGRE's renderers).

Z-pass counts the volume faces between the near plane and the visible point, so it is exact
unless some volume contains a point of the near-plane rectangle R.  A point Q of R lies in the
shadow volume of a triangle only if the segment from Q to the light crosses that triangle; that
segment lies in the convex hull of the light and R (the "near-clip volume": a pyramid for a point
light, an infinite prism toward the light for a directional one).  So a caster whose bounding
box is separated from that hull can safely use z-pass; every other caster uses z-fail, which
costs caps.  The test is conservative: it may choose z-fail where z-pass would have worked,
never the reverse.
"""

from __future__ import annotations

import numpy as np

from shadowvol.cameras import look_at_basis
from shadowvol.raster.projection import cross3, near_rectangle
from shadowvol.raster.volumes.cpu import CpuVolumes
from shadowvol.raster.volumes.gpu import GpuVolumes
from shadowvol.scene import Camera

# A box counts as outside a plane of the near-clip volume only if all its corners are farther
# than this fraction of the scene's extent: rounding must never make the test unsafe.
NEAR_CLIP_MARGIN = 1e-6
# |cos| between the light direction (or light offset) and the near plane below which the light
# counts as lying IN the near plane; the hull is then flat and every caster takes z-fail.
DEGENERATE_LIGHT = 1e-9
# A directional light's hull reaches to infinity toward the light; the box test below stands in a
# point this many scene extents away (every caster lies within one extent of the near plane, so
# the prism beyond that point cannot touch one).
FAR_APEX_EXTENTS = 1e6
# The z-pass clip box (`zpass_clip_planes`) is grown by this fraction of the scene's extent on
# every side: far more than float32 rounding of the planes, the vertices and the interpolated
# clip distances (~1e-6 of the extent), so no fragment that could count is clipped.
ZPASS_BOX_MARGIN = 1e-3


def near_clip_planes(camera: Camera, size: tuple[float, float], light4: np.ndarray
                     ) -> np.ndarray | None:
    """(5, 4) float64 planes (n, d) of the near-clip volume, n . x + d <= 0 inside, or None
    when the light lies in the near plane (degenerate hull)."""
    rect = near_rectangle(camera, size)                                 # (4, 3)
    centre = rect.mean(axis=0)
    forward = -look_at_basis(camera)[2]   # target - eye, normalised, for a look-at camera
    toward_light = light4[:3] - light4[3] * centre                        # centre -> light
    scale = np.linalg.norm(toward_light)
    side = float(forward @ toward_light)
    if scale == 0.0 or abs(side) <= DEGENERATE_LIGHT * scale:
        return None
    planes = []
    # the near plane, the light's side inside
    n = -forward if side > 0 else forward
    planes.append(np.append(n, -n @ centre))
    for p, q in zip(rect, np.roll(rect, -1, axis=0)):
        n = cross3(q - p, light4[:3] - light4[3] * p)
        if n @ (centre - p) > 0:
            n = -n
        planes.append(np.append(n / np.linalg.norm(n), -(n / np.linalg.norm(n)) @ p))
    return np.array(planes)


CULL_NEAR_MARGIN = 1e-6  # of the scene's extent: a box touching the near plane is not culled


def needs_zfail(bounds: np.ndarray, camera: Camera, size: tuple[float, float], light4: np.ndarray,
                extent: float) -> np.ndarray:
    """(n,) bool: True for every caster whose volume the near plane may cut.

    bounds : (n, 2, 3) float64 axis-aligned boxes (min, max) of the casters.
    """
    planes = near_clip_planes(camera, size, light4)
    if planes is None:
        return np.ones(len(bounds), bool)
    # the 8 corners of each box: (n, 8, 3)
    pick = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    corners = np.stack([bounds[:, pick[:, 0], 0], bounds[:, pick[:, 1], 1],
                        bounds[:, pick[:, 2], 2]], axis=-1)
    margin = NEAR_CLIP_MARGIN * extent
    dist = corners @ planes[:, :3].T + planes[:, 3]                       # (n, 8, 5)
    outside_a_hull_plane = (dist > margin).all(axis=1).any(axis=1)
    # and the box's own faces against the hull's corners (a separating-axis test on the box's
    # three axes too): a flat floor below the hull is separated only this way.
    rect = near_rectangle(camera, size)
    apex = (light4[:3] if light4[3]
            else rect.mean(axis=0) + light4[:3] * (FAR_APEX_EXTENTS * extent))
    hull = np.concatenate([rect, apex[None]])                             # (5, 3)
    # every hull corner below a box's low face (above its high face) on one axis: the hull's
    # largest (smallest) coordinate is, an (n, 3) test instead of (n, 5, 3)
    below = (hull.max(axis=0) < bounds[:, 0, :] - margin).any(axis=1)
    above = (hull.min(axis=0) > bounds[:, 1, :] + margin).any(axis=1)
    return ~(outside_a_hull_plane | below | above)


def _none(bounds: np.ndarray, *_) -> np.ndarray:
    return np.zeros(len(bounds), bool)


def _every(bounds: np.ndarray, *_) -> np.ndarray:
    return np.ones(len(bounds), bool)


# The choices a frame is drawn with, each name mapped to what it means (the one table: the
# renderer checks its arguments against it and draws with what it names).
# method -> which casters count with z-fail: f(bounds, camera, size, light4, extent) (n,) bool
METHOD_CHOICES = {"auto": needs_zfail, "zpass": _none, "zfail": _every}
# silhouettes -> the volume builder (`volumes.builder.VolumeBuilder`) that finds them
SILHOUETTE_CHOICES = {"cpu": CpuVolumes, "gpu": GpuVolumes}
METHODS = tuple(METHOD_CHOICES)
SILHOUETTES = tuple(SILHOUETTE_CHOICES)


def check_choices(method: str, silhouettes: str) -> None:
    """ValueError unless `method` and `silhouettes` are names of the tables above."""
    if method not in METHOD_CHOICES:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    if silhouettes not in SILHOUETTE_CHOICES:
        raise ValueError(f"silhouettes must be 'cpu' or 'gpu', got {silhouettes!r}")


def choose(method: str, bounds: np.ndarray, camera: Camera, size: tuple[float, float],
           light4: np.ndarray, extent: float) -> np.ndarray:
    """(n,) bool: which casters use z-fail under `method` ("auto", "zpass" or "zfail")."""
    if method not in METHOD_CHOICES:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    return METHOD_CHOICES[method](bounds, camera, size, light4, extent)


def zpass_clip_planes(bounds: np.ndarray, camera: Camera, size: tuple[float, float],
                      extent: float) -> np.ndarray:
    """(6, 4) float64 planes (n, d) of a box, n . x + d w >= 0 inside (x homogeneous, so a
    point at infinity (x, 0) is inside when its direction does not leave through the plane),
    that holds every caster's box and the near rectangle, grown by ZPASS_BOX_MARGIN * extent.

    Z-pass counts the volume faces crossed between the near plane and the visible point.  Both
    ends of that segment lie in this convex box (a visible point lies on a triangle, inside its
    object's box), so the whole segment does: a fragment of a volume face outside the box is
    never in front of a visible point, and clipping the faces to the box leaves every count at
    a covered pixel exactly as it was, whatever the caster or the method.  It saves the fill of
    the volumes beyond the receivers, out to infinity.  Uncovered pixels (nothing visible)
    count differently, so the stencil read-back must not use it.
    """
    rect = near_rectangle(camera, size)
    margin = ZPASS_BOX_MARGIN * extent
    lo = np.minimum(bounds[:, 0].min(axis=0), rect.min(axis=0)) - margin
    hi = np.maximum(bounds[:, 1].max(axis=0), rect.max(axis=0)) + margin
    planes = np.zeros((6, 4))
    for axis in range(3):
        planes[2 * axis, axis], planes[2 * axis, 3] = 1.0, -lo[axis]         # x >= lo
        planes[2 * axis + 1, axis], planes[2 * axis + 1, 3] = -1.0, hi[axis]  # x <= hi
    return planes


def cullable(bounds: np.ndarray, outward_convex: np.ndarray, camera: Camera,
             extent: float) -> np.ndarray:
    """(n,) bool: objects whose back faces the geometry pass may cull without changing what is
    visible: closed convex meshes wound outward (`overflow.detect.convex_orientation` +1) whose
    whole box lies beyond the near plane (by CULL_NEAR_MARGIN * extent), so the eye is outside the
    body and no view ray starts inside it.  A view ray from outside a convex body meets it
    first through a front face; the back faces it meets later lie behind that front face, so
    in exact arithmetic the depth test rejects them.  In float32 it is not exact: near a
    silhouette edge a back face's depth can round nearer than the front face's, win, and show
    its own normal; culled, the front face shows there instead (one pixel of
    scenes/whitted.toml, lit instead of unlit).  Hence `Renderer.cull_back_faces` is off by
    default.

    bounds : (n, 2, 3) float64 boxes; outward_convex : (n,) bool."""
    forward = -look_at_basis(camera)[2]   # target - eye, normalised, for a look-at camera
    pick = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    corners = np.stack([bounds[:, pick[:, 0], 0], bounds[:, pick[:, 1], 1],
                        bounds[:, pick[:, 2], 2]], axis=-1)                  # (n, 8, 3)
    depth = (corners - camera.eye) @ forward                                # (n, 8)
    beyond = (depth > camera.near + CULL_NEAR_MARGIN * extent).all(axis=1)
    return outward_convex & beyond
