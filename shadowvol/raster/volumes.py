"""Shadow-volume geometry for one light at a time: side quads, near caps and far caps.

Two builders with one interface (`prepare(light4)`, `draw_sides(objects)`,
`draw_caps(objects, near)`):

- `CpuVolumes`: silhouettes by the multiplicity rule in numpy (`silhouettes`), side quads uploaded
  per light, caps drawn from the scene soup through index lists split by triangle sign.
- `GpuVolumes`: a static edge buffer (Pečiva et al. 2013) and a geometry shader computing each
  edge's multiplicity, and a vertex shader choosing each triangle's caps, all on the GPU; nothing
  per light but uniforms.

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
unlit by n . l anyway.  tests/test_gl_exact.py checks a lit floor, an open quad seen from its lit
side and a closed mesh under z-fail.
"""

from __future__ import annotations

import moderngl
import numpy as np

from shadowvol.raster import glsl
from shadowvol.raster.geometry import SceneGeometry
from shadowvol.raster.silhouettes import (
    edge_multiplicity,
    quads_to_triangles,
    side_quads,
    topology_signs,
)

MAX_OPPOSITE = 4  # opposite vertices per edge record (silhouette.geom emits at most 4 quads)
# front face to use so that a cap of triangles of sign s, drawn in their own winding, faces out
# of its volume: the near cap faces the light, the far cap faces away from it
_FRONT_FACE = {(True, 1): "ccw", (True, -1): "cw", (False, 1): "cw", (False, -1): "ccw"}


class CpuVolumes:
    """Shadow volumes from CPU silhouettes.  Programs are made here; call `release()`."""

    def __init__(self, ctx: moderngl.Context, geometry: SceneGeometry):
        self.ctx, self.geometry = ctx, geometry
        self.side_program = glsl.program(ctx, "volume_side.vert", "volume.frag")
        self.clip_program = glsl.program(ctx, "volume_side.vert", "volume.frag",
                                         defines={"ZPASS_CLIP": 1})
        self.near_program = glsl.program(ctx, "scene.vert", "volume.frag")
        self.far_program = glsl.program(ctx, "far_cap.vert", "volume.frag")
        self.programs = (self.side_program, self.clip_program, self.near_program,
                         self.far_program)
        self.side_buffer = ctx.buffer(reserve=64, dynamic=True)
        self.index_buffer = ctx.buffer(reserve=64, dynamic=True)
        self.side_vao = ctx.vertex_array(self.side_program,
                                         [(self.side_buffer, "4f", "in_position")])
        self.clip_vao = ctx.vertex_array(self.clip_program,
                                         [(self.side_buffer, "4f", "in_position")])
        self.near_vao = ctx.vertex_array(self.near_program,
                                         geometry.soup_bindings(self.near_program),
                                         index_buffer=self.index_buffer, index_element_size=4)
        self.far_vao = ctx.vertex_array(self.far_program,
                                        geometry.soup_bindings(self.far_program),
                                        index_buffer=self.index_buffer, index_element_size=4)
        self.light4 = None
        self._signs: list[np.ndarray] = []                        # per object, this light
        self._sides: dict[int, tuple[int, int]] = {}              # object -> (first, count)
        self._caps: dict[tuple[int, int], tuple[int, int]] = {}   # (object, sign) -> (first, n)
        self._capped: tuple[int, ...] | None = None               # objects in index_buffer

    def prepare(self, light4: np.ndarray) -> None:
        """Compute and upload this light's side quads.  Cap index lists are built on the first
        `draw_caps` (most frames z-fail few casters or none, and a cap list is 3 indices per
        triangle).  Sets the light on the volume programs."""
        self.light4 = light4
        _set_light(self.programs, light4)
        sides = []
        n_side = 0
        self._sides.clear()
        self._signs.clear()
        self._capped = None
        for rng, topo in zip(self.geometry.ranges, self.geometry.topologies):
            signs = topology_signs(topo, light4)
            self._signs.append(signs)
            multiplicity = edge_multiplicity(topo, signs)
            # A caster whose multiplicities are all even (a closed, consistently wound mesh
            # gives 2 on every silhouette edge) stores each quad once, m / 2 copies, and is
            # drawn twice: the same quads as |m| copies, in another order, and stencil
            # INCR_WRAP / DECR_WRAP commute.  See `draw_sides` for drawing it once.
            repeat = 2 if multiplicity.any() and not (multiplicity & 1).any() else 1
            tris = quads_to_triangles(side_quads(topo, multiplicity // repeat, light4))
            sides.append(tris)
            self._sides[rng.index] = (n_side, len(tris), repeat)
            n_side += len(tris)
        # float32 at upload: what GL draws; the quads were built in float64 from the welded
        # positions, which are the drawn vertices exactly, so edges meet the caps exactly
        _upload(self.side_buffer, np.concatenate(sides).astype(np.float32))

    def _prepare_caps(self, objects: tuple[int, ...]) -> None:
        """Upload the cap index lists (soup vertices of the triangles of each sign) of
        `objects` for the prepared light."""
        if self._capped == objects:
            return
        indices, n_index = [], 0
        self._caps.clear()
        for i in objects:
            rng = self.geometry.ranges[i]
            for sign in (1, -1):
                t = np.flatnonzero(self._signs[i] == sign) + rng.first
                idx = (3 * t[:, None] + np.arange(3)).reshape(-1)
                indices.append(idx)
                self._caps[i, sign] = (n_index, len(idx))
                n_index += len(idx)
        _upload(self.index_buffer, np.concatenate(indices).astype(np.int32))
        self._capped = objects

    def draw_sides(self, objects, halve: bool = False, clipped: bool = False) -> None:
        """Draw the side quads of `objects`.  `clipped`: with the program that writes the
        distances to the z-pass clip box (`methods.zpass_clip_planes`; z-pass only).
        `halve`: draw the quads of casters whose multiplicities are all even once (m / 2
        copies), not twice.

        Halving is for z-pass casters only, and only when the caller needs just "count == 0":
        the z-pass count at a pixel is linear in the multiplicities, so such a caster adds
        exactly half its count, an integer.  Where z-pass is valid (the near rectangle lies in
        none of the caster's volumes, as `methods.needs_zfail` guarantees) every caster's count
        is the number of its triangles between the point and the light, >= 0, so the sum is 0
        exactly when it was 0 before.  (The stencil's 8-bit wrap, documented in `renderer`,
        needs 256 layers either way.)  Z-fail casters must not be halved: their caps count 1
        per triangle."""
        vao = self.clip_vao if clipped else self.side_vao
        for i in objects:
            first, count, repeat = self._sides[i]
            if count:
                for _ in range(1 if halve else repeat):
                    vao.render(moderngl.TRIANGLES, vertices=count, first=first)

    def draw_caps(self, objects, near: bool) -> None:
        if not near and self.light4[3] == 0.0:
            return  # a directional light's far cap is one point at infinity
        objects = tuple(int(i) for i in objects)
        if not objects:
            return
        self._prepare_caps(objects)
        vao = self.near_vao if near else self.far_vao
        for sign in (1, -1):
            self.ctx.front_face = _FRONT_FACE[near, sign]
            for i in objects:
                first, count = self._caps[i, sign]
                if count:
                    vao.render(moderngl.TRIANGLES, vertices=count, first=first)
        self.ctx.front_face = "ccw"

    def release(self) -> None:
        for obj in (self.side_vao, self.clip_vao, self.near_vao, self.far_vao, self.side_buffer,
                    self.index_buffer, *self.programs):
            obj.release()


class GpuVolumes:
    """Shadow volumes from GPU silhouettes (geometry shaders).  Call `release()`."""

    def __init__(self, ctx: moderngl.Context, geometry: SceneGeometry):
        self.ctx, self.geometry = ctx, geometry
        self.edge_program = glsl.program(ctx, "edge.vert", "volume.frag", "silhouette.geom")
        self.clip_program = glsl.program(ctx, "edge.vert", "volume.frag", "silhouette.geom",
                                         defines={"ZPASS_CLIP": 1})
        self.near_program = glsl.program(ctx, "caps.vert", "volume.frag")
        self.far_program = glsl.program(ctx, "caps.vert", "volume.frag",
                                        defines={"FAR_CAP": 1})
        self.programs = (self.edge_program, self.clip_program, self.near_program,
                         self.far_program)
        # every soup vertex also carries its triangle's other two corners (float32, as drawn)
        corners = geometry.soup_corners()                                # (M, 3, 3)
        self.corner_buffers = [ctx.buffer(np.repeat(corners[:, k], 3, axis=0).tobytes())
                               for k in (1, 2)]
        cap_bindings = [(self.corner_buffers[0], "3f", "in_corner1"),
                        (self.corner_buffers[1], "3f", "in_corner2")]
        self.near_vao = ctx.vertex_array(
            self.near_program, geometry.soup_bindings(self.near_program) + cap_bindings)
        self.far_vao = ctx.vertex_array(
            self.far_program, geometry.soup_bindings(self.far_program) + cap_bindings)
        records, self._records = [], {}
        n = 0
        for rng, topo in zip(geometry.ranges, geometry.topologies):
            rec = edge_records(topo)
            records.append(rec)
            self._records[rng.index] = (n, len(rec))
            n += len(rec)
        self.edge_buffer = ctx.buffer(np.concatenate(records).tobytes())
        self.edge_vao, self.clip_vao = (ctx.vertex_array(program, [
            (self.edge_buffer, "3f 3f 3f 3f 3f 3f 1i", "in_a", "in_b", "in_c0", "in_c1",
             "in_c2", "in_c3", "in_count")]) for program in (self.edge_program,
                                                             self.clip_program))
        self.light4 = None

    def prepare(self, light4: np.ndarray) -> None:
        self.light4 = light4  # everything else happens in the shaders
        _set_light(self.programs, light4)

    def draw_sides(self, objects, halve: bool = False, clipped: bool = False) -> None:
        """Draw the side quads of `objects`; `clipped` as in `CpuVolumes.draw_sides`.  `halve`
        is accepted for the common interface and ignored: the geometry shader sees one edge at
        a time, never a whole caster's multiplicities, so it cannot know that they are all
        even."""
        vao = self.clip_vao if clipped else self.edge_vao
        for i in objects:
            first, count = self._records[i]
            if count:
                vao.render(moderngl.POINTS, vertices=count, first=first)

    def draw_caps(self, objects, near: bool) -> None:
        if not near and self.light4[3] == 0.0:
            return
        program, vao = (self.near_program, self.near_vao) if near else (self.far_program,
                                                                         self.far_vao)
        for sign in (1, -1):
            program["u_cap_sign"].value = sign
            self.ctx.front_face = _FRONT_FACE[near, sign]
            for i in objects:
                rng = self.geometry.ranges[i]
                vao.render(moderngl.TRIANGLES, vertices=3 * rng.count,
                                    first=3 * rng.first)
        self.ctx.front_face = "ccw"

    def release(self) -> None:
        for obj in (self.edge_vao, self.clip_vao, self.near_vao, self.far_vao, self.edge_buffer,
                    *self.corner_buffers, *self.programs):
            obj.release()


# float32 positions: exactly the scene soup's float32 vertices (exact welding), so the geometry
# shader's tri_sign sees the same numbers as caps.vert does for the same triangle
EDGE_RECORD = np.dtype([("a", "<f4", 3), ("b", "<f4", 3), ("c", "<f4", (MAX_OPPOSITE, 3)),
                        ("count", "<i4")])


def edge_records(topo) -> np.ndarray:
    """(r,) EDGE_RECORD: every edge with its opposite vertices, MAX_OPPOSITE per record; an
    edge on n triangles takes ceil(n / MAX_OPPOSITE) records (multiplicity is additive)."""
    per_edge = topo.triangles_per_edge                                  # (e,)
    n_rec = -(-per_edge // MAX_OPPOSITE)
    rec_first = np.concatenate([[0], np.cumsum(n_rec)[:-1]])
    inc_first = np.concatenate([[0], np.cumsum(per_edge)[:-1]])
    rank = np.arange(len(topo.inc_edge)) - inc_first[topo.inc_edge]      # rank on its edge
    rec = rec_first[topo.inc_edge] + rank // MAX_OPPOSITE
    out = np.zeros(int(n_rec.sum()), EDGE_RECORD)
    rec_edge = np.repeat(np.arange(len(per_edge)), n_rec)
    out["a"] = topo.vertices[topo.edges[rec_edge, 0]]
    out["b"] = topo.vertices[topo.edges[rec_edge, 1]]
    out["c"][rec, rank % MAX_OPPOSITE] = topo.vertices[topo.inc_opposite]
    out["count"] = np.bincount(rec, minlength=len(out))
    return out


def _upload(buffer: moderngl.Buffer, data: np.ndarray) -> None:
    raw = data.tobytes()
    if len(raw) > buffer.size:
        buffer.orphan(max(len(raw), 2 * buffer.size))
    if raw:
        buffer.write(raw)


def _set_light(programs, light4: np.ndarray) -> None:
    """The one place `u_light` of the volume programs is set: by the builder that holds it."""
    for p in programs:
        glsl.set_uniform(p, "u_light", tuple(float(x) for x in light4))
