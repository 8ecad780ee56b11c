"""Shadow-volume geometry for one light at a time: side quads, near caps and far caps.

Two builders with one interface (`VolumeBuilder`: `prepare(light4)`, `draw_sides(objects)`,
`draw_caps(objects, near)`), each in its own module:

- `volumes.cpu.CpuVolumes`: silhouettes by the multiplicity rule in numpy (`silhouettes`), side
  quads uploaded per light, caps drawn from the scene soup through index lists split by sign.
- `volumes.gpu.GpuVolumes`: a static edge buffer (Pečiva et al. 2013) and a geometry shader
  computing each edge's multiplicity, and a vertex shader choosing each triangle's caps, all on
  the GPU; nothing per light but uniforms.

Caps, and why a lit surface is never shadowed by its own cap
------------------------------------------------------------
Every triangle casts (two-sided surfaces), so every triangle T is the near cap of its own volume
and the visible surface point X on T lies exactly ON that cap.  In z-fail the stencil counts
the volume faces behind X; the view ray enters T's volume at X (when the eye sees T's lit side)
and leaves it somewhere behind, so the entry at X must count as "behind X" for the two to
cancel.  We make that exact rather than approximate: near caps are drawn by the same vertex
shader (scene.vert, `invariant gl_Position`) from the same vertex buffer in the same vertex order,
without depth clamp, so their depths equal the depth buffer's bit for bit, and the volume passes
use the depth test "strictly nearer" (camera.NEARER), under which a tie FAILS, i.e. counts as
behind.  Orientation (which of
front/back face the cap is) is set with the front-face state, never by reordering vertices,
because reordering could change the rasterized depths.  A polygon offset was rejected: it
only moves the problem to surfaces at another slope.  When the eye sees T's unlit side, X is
unlit by n . l anyway.  tests/raster/test_exact.py checks a lit floor, an open quad seen from its lit
side and a closed mesh under z-fail.
"""

from __future__ import annotations

from typing import Protocol

import moderngl
import numpy as np

from shadowvol.raster import glsl, guard
from shadowvol.raster.geometry import SceneGeometry, merged_runs
from shadowvol.raster.projection import in_frame

MAX_OPPOSITE = 4  # opposite vertices per edge record (silhouette.geom emits at most 4 quads)
# front face to use so that a cap of triangles of sign s, drawn in their own winding, faces out
# of its volume: the near cap faces the light, the far cap faces away from it
FRONT_FACE = {(True, 1): "ccw", (True, -1): "cw", (False, 1): "cw", (False, -1): "ccw"}


class VolumeBuilder(Protocol):
    """What the passes use of a volume builder (`CpuVolumes`, `GpuVolumes`).

    light4 : (4,) float64, the prepared homogeneous light (None before the first `prepare`);
    `programs`: every volume program, for the camera and clip uniforms."""

    geometry: SceneGeometry
    light4: np.ndarray | None

    @property
    def programs(self) -> tuple[moderngl.Program, ...]: ...

    def counting_programs(self) -> tuple[moderngl.Program, ...]: ...

    def new_frame(self) -> None: ...

    def prepare(self, light4: np.ndarray) -> None: ...

    def draw_sides(self, objects, halve: bool = False, clipped: bool = False,
                   each=None) -> None: ...

    def draw_caps(self, objects, near: bool, each=None) -> None: ...

    def release(self) -> None: ...


def far_cap_pieces(geometry: SceneGeometry, light4: np.ndarray, signs: list[np.ndarray]
                   ) -> list[tuple[int, np.ndarray]]:
    """The far caps of the huge triangles the geometry pass cut (`SceneGeometry.holes`), for a
    point light: each triangle projected to infinity, (V - L, 0), cut to the guard pyramid in
    homogeneous coordinates (`guard.cut`), wound to face out of its volume when drawn with the
    front face ccw (a sign-1 far cap is drawn cw: `FRONT_FACE`; at infinity there are no
    depth ties, so the order of its corners is free).  signs : per object, the triangles'
    signs.  Returns (object, (n, 4) float32 homogeneous frame corners) per object; none for a
    directional light (its far cap is a point)."""
    light = in_frame(light4, geometry.origin)
    out = []
    if light[3] == 0.0 or not len(geometry.holes):
        return out
    planes = geometry.guard[0]
    objects = geometry.triangle_objects[geometry.holes]
    corners = geometry.frame_corners(geometry.holes)
    for i in np.unique(objects):
        mine = []
        for t, frame in zip(geometry.holes[objects == i], corners[objects == i]):
            sign = signs[i][t - geometry.ranges[i].first]
            if sign == 0:
                continue
            cap = np.zeros((3, 4))
            cap[:, :3] = frame.astype(np.float64) * light[3] - light[:3]
            tris = guard.cut(cap, planes)
            if len(tris):   # a far cap wholly outside the guard pyramid leaves none
                mine.append(tris[:, ::-1] if sign == 1 else tris)
        if mine:
            out.append((int(i), np.concatenate(mine).reshape(-1, 4).astype(np.float32)))
    return out


def runs(ranges) -> list[tuple[int, int]]:
    """(first, count) ranges, empty ones dropped and ranges that continue each other merged:
    one draw call per run instead of one per object."""
    table = np.array(list(ranges), np.int64).reshape(-1, 2)
    return runs_of(table[:, 0], table[:, 1])


def runs_of(first: np.ndarray, count: np.ndarray) -> list[tuple[int, int]]:
    """`runs` of the ranges (first[k], count[k]), in numpy."""
    first = np.asarray(first, np.int64)
    starts, ends = merged_runs(first, first + np.asarray(count, np.int64))
    return list(zip(starts.tolist(), (ends - starts).tolist()))



def set_light(programs, light4: np.ndarray, origin: np.ndarray) -> None:
    """The one place `u_light` of the volume programs is set: by the builder that holds it,
    in the frame of `origin`."""
    light = in_frame(light4, origin)
    for p in programs:
        glsl.set_uniform(p, "u_light", tuple(float(x) for x in light))
