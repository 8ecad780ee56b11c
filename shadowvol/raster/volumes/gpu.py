"""Shadow volumes from GPU silhouettes (`GpuVolumes`): a static edge buffer (Pečiva et al. 2013)
and a geometry shader computing each edge's multiplicity, and a vertex shader choosing each
triangle's caps, all on the GPU; nothing per light but uniforms.  Why caps never shadow their
own surface: `volumes`."""

from __future__ import annotations

import moderngl
import numpy as np

from shadowvol.raster import glsl
from shadowvol.raster.geometry import SceneGeometry
from shadowvol.raster.projection import to_frame
from shadowvol.raster.volumes.silhouettes import topology_signs
from shadowvol.raster.volumes.builder import (
    FRONT_FACE,
    MAX_OPPOSITE,
    far_cap_pieces,
    runs,
    runs_of,
    set_light,
)


class GpuVolumes:
    """Shadow volumes from GPU silhouettes (geometry shaders).  Call `release()`."""

    def __init__(self, ctx: moderngl.Context, geometry: SceneGeometry):
        self.ctx, self.geometry = ctx, geometry
        (self.edge_program, self.clip_program, self.near_program,
         self.far_program) = self._programs("volume.frag")
        # the cut far caps of huge triangles (`far_cap_pieces`), homogeneous triangles
        self.piece_program = glsl.program(ctx, "volume_side.vert", "volume.frag")
        self._stencil = (self.edge_program, self.clip_program, self.near_program,
                         self.far_program, self.piece_program)
        self._counting: tuple[moderngl.Program, ...] = ()
        self._counting_vaos: tuple[moderngl.VertexArray, ...] = ()
        self._counting_far_vao: moderngl.VertexArray | None = None
        self._far: dict[int, tuple[int, int]] = {}
        self._far_key = None
        self._far_buffer: moderngl.Buffer | None = None
        self._far_vao: moderngl.VertexArray | None = None
        # every soup vertex also carries its triangle's other two corners (float32, as drawn)
        self.corner_buffers = [ctx.buffer(data.tobytes()) for data in self._corner_data()]
        self._records = {}
        n = 0
        for rng, topo in zip(geometry.ranges, geometry.topologies):
            count = len(edge_records(topo, geometry.origin, counts_only=True))
            self._records[rng.index] = (n, count)
            n += count
        # the same, (n_objects, 2), for the draws of all casters at once (`draw_sides`)
        self._record_table = np.array([self._records[rng.index] for rng in geometry.ranges],
                                      np.int64).reshape(-1, 2)
        self.edge_buffer = ctx.buffer(self._edge_data().tobytes())
        self._moves, self._cuts = geometry.moves, geometry.cuts
        self.edge_vao, self.clip_vao, self.near_vao, self.far_vao = self._vaos(
            self._stencil[:4])
        self.light4 = None

    def _programs(self, fragment: str) -> tuple[moderngl.Program, ...]:
        """sides (edge records), sides clipped to the z-pass box, near caps, far caps."""
        return (glsl.program(self.ctx, "edge.vert", fragment, "silhouette.geom"),
                glsl.program(self.ctx, "edge.vert", fragment, "silhouette.geom",
                             defines={"ZPASS_CLIP": 1}),
                glsl.program(self.ctx, "caps.vert", fragment),
                glsl.program(self.ctx, "caps.vert", fragment, defines={"FAR_CAP": 1}))

    def _vaos(self, programs) -> tuple[moderngl.VertexArray, ...]:
        """The vaos of `_programs`' four programs, in their order."""
        edge, clip, near, far = programs
        cap_bindings = [(self.corner_buffers[0], "3f", "in_corner1"),
                        (self.corner_buffers[1], "3f", "in_corner2")]
        return tuple(self.ctx.vertex_array(program, [
            (self.edge_buffer, "3f 3f 3f 3f 3f 3f 1i", "in_a", "in_b", "in_c0", "in_c1",
             "in_c2", "in_c3", "in_count")]) for program in (edge, clip)) + tuple(
            self.ctx.vertex_array(program, self.geometry.soup_bindings(program) + cap_bindings)
            for program in (near, far))

    @property
    def programs(self) -> tuple[moderngl.Program, ...]:
        """As `CpuVolumes.programs`."""
        return self._stencil + self._counting

    def counting_programs(self) -> tuple[moderngl.Program, ...]:
        """As `CpuVolumes.counting_programs`."""
        if not self._counting:
            self._counting = self._programs("caster_count.frag") + (
                glsl.program(self.ctx, "volume_side.vert", "caster_count.frag"),)
            self._counting_vaos = self._vaos(self._counting[:4])
            if self.light4 is not None:
                set_light(self._counting, self.light4, self.geometry.origin)
        return self._counting

    def new_frame(self) -> None:
        """Nothing is kept per light (the common interface)."""

    def _corner_data(self) -> list[np.ndarray]:
        """The soup's, then the pieces' (their triangle's) second and third corners."""
        corners = self.geometry.soup_corners()                           # (M, 3, 3) float32
        t = np.concatenate([np.arange(len(corners)), self.geometry.piece_of])
        return [np.repeat(corners[t, k], 3, axis=0) for k in (1, 2)]

    def _edge_data(self) -> np.ndarray:
        return np.concatenate([edge_records(topo, self.geometry.origin)
                               for topo in self.geometry.topologies])

    def prepare(self, light4: np.ndarray) -> None:
        self.light4 = light4  # everything else happens in the shaders
        set_light(self.programs, light4, self.geometry.origin)
        geometry = self.geometry
        if self._moves != geometry.moves or self._cuts != geometry.cuts:
            # the frame moved or the pieces of huge triangles changed: rewrite, growing
            for buf, data in zip(self.corner_buffers, self._corner_data()):
                if data.nbytes > buf.size:
                    buf.orphan(data.nbytes)
                buf.write(data.tobytes())
        if self._moves != geometry.moves:
            self.edge_buffer.write(self._edge_data().tobytes())
        self._moves, self._cuts = geometry.moves, geometry.cuts
        key = (geometry.views, np.asarray(light4, np.float64).tobytes())
        if self._far_key != key:
            self._far_key, self._far = key, {}
            if len(geometry.holes):
                # the signs in float64 from the topology, as the CPU silhouettes'; the GPU's
                # own (float32, tri_sign) could differ only for a triangle edge-on to the light
                signs = {int(i): topology_signs(geometry.topologies[i], light4)
                         for i in np.unique(geometry.triangle_objects[geometry.holes])}
                pieces = far_cap_pieces(geometry, light4, signs)
                data, at = [], 0
                for i, tris in pieces:
                    self._far[i] = (at, len(tris))
                    data.append(tris)
                    at += len(tris)
                if data:
                    self._write_far(np.concatenate(data))

    def _write_far(self, data: np.ndarray) -> None:
        if self._far_buffer is None:
            self._far_buffer = self.ctx.buffer(reserve=data.nbytes)
            self._far_vao = self.ctx.vertex_array(
                self.piece_program, [(self._far_buffer, "4f", "in_position")])
        elif data.nbytes > self._far_buffer.size:
            self._far_buffer.orphan(data.nbytes)
        self._far_buffer.write(np.ascontiguousarray(data).tobytes())

    def draw_sides(self, objects, halve: bool = False, clipped: bool = False,
                   each=None) -> None:
        """Draw the side quads of `objects`; `clipped` and `each` as in
        `CpuVolumes.draw_sides`.  `halve` is accepted for the common interface and ignored:
        the geometry shader sees one edge at a time, never a whole caster's multiplicities, so
        it cannot know that they are all even."""
        if each is None:
            vao = self.clip_vao if clipped else self.edge_vao
        else:
            self.counting_programs()
            vao = self._counting_vaos[1 if clipped else 0]
        if each is None:   # the records of objects next to each other in one draw
            objects = np.asarray(objects, np.int64).reshape(-1)
            table = self._record_table
            for first, count in runs_of(table[objects, 0], table[objects, 1]):
                vao.render(moderngl.POINTS, vertices=count, first=first)
            return
        for i in objects:
            first, count = self._records[i]
            if count:
                each(vao.program, i)
                vao.render(moderngl.POINTS, vertices=count, first=first)

    def draw_caps(self, objects, near: bool, each=None) -> None:
        if not near and self.light4[3] == 0.0:
            return
        if each is None:
            vao = self.near_vao if near else self.far_vao
        else:
            self.counting_programs()
            vao = self._counting_vaos[2 if near else 3]
        for sign in (1, -1):
            vao.program["u_cap_sign"].value = sign
            self.ctx.front_face = FRONT_FACE[near, sign]
            # near caps as the geometry pass drew them (huge triangles' pieces); far caps whole
            # (see `CpuVolumes._prepare_caps`): huge ones' far caps cut, drawn below
            if each is None:
                spans = self.geometry.spans(sorted(int(i) for i in objects), pieces=near)
                for first, count in spans:
                    vao.render(moderngl.TRIANGLES, vertices=3 * count, first=3 * first)
                continue
            for i in objects:
                each(vao.program, i)
                for first, count in self.geometry.spans([int(i)], pieces=near):
                    vao.render(moderngl.TRIANGLES, vertices=3 * count, first=3 * first)
        self.ctx.front_face = "ccw"
        if not near and self._far:
            if each is None:
                for first, count in runs(self._far[i] for i in objects if i in self._far):
                    self._far_vao.render(moderngl.TRIANGLES, vertices=count, first=first)
                return
            if self._counting_far_vao is None:   # the buffer is made once, then orphaned
                self._counting_far_vao = self.ctx.vertex_array(
                    self._counting[4], [(self._far_buffer, "4f", "in_position")])
            for i in (i for i in objects if i in self._far):
                each(self._counting[4], i)
                first, count = self._far[i]
                self._counting_far_vao.render(moderngl.TRIANGLES, vertices=count, first=first)

    def release(self) -> None:
        for obj in (self._far_vao, self._counting_far_vao, self._far_buffer):
            if obj is not None:
                obj.release()
        for obj in (self.edge_vao, self.clip_vao, self.near_vao, self.far_vao,
                    *self._counting_vaos, self.edge_buffer, *self.corner_buffers,
                    *self.programs):
            obj.release()


# float32 positions: exactly the scene soup's float32 vertices (exact welding), so the geometry
# shader's tri_sign sees the same numbers as caps.vert does for the same triangle
EDGE_RECORD = np.dtype([("a", "<f4", 3), ("b", "<f4", 3), ("c", "<f4", (MAX_OPPOSITE, 3)),
                        ("count", "<i4")])


def edge_records(topo, origin: np.ndarray | None = None, counts_only: bool = False
                 ) -> np.ndarray:
    """(r,) EDGE_RECORD: every edge with its opposite vertices, MAX_OPPOSITE per record, in the
    frame of `origin` (3,) float64 (default: world space); an edge on n triangles takes
    ceil(n / MAX_OPPOSITE) records (multiplicity is additive).  `counts_only`: the records' count is right, not their
    positions (cheap)."""
    per_edge = topo.triangles_per_edge                                  # (e,)
    n_rec = -(-per_edge // MAX_OPPOSITE)
    rec_first = np.concatenate([[0], np.cumsum(n_rec)[:-1]])
    inc_first = np.concatenate([[0], np.cumsum(per_edge)[:-1]])
    rank = np.arange(len(topo.inc_edge)) - inc_first[topo.inc_edge]      # rank on its edge
    rec = rec_first[topo.inc_edge] + rank // MAX_OPPOSITE
    out = np.zeros(int(n_rec.sum()), EDGE_RECORD)
    rec_edge = np.repeat(np.arange(len(per_edge)), n_rec)
    out["count"] = np.bincount(rec, minlength=len(out))
    if counts_only:
        return out
    vertices = to_frame(topo.vertices, np.zeros(3) if origin is None else origin)
    out["a"] = vertices[topo.edges[rec_edge, 0]]
    out["b"] = vertices[topo.edges[rec_edge, 1]]
    out["c"][rec, rank % MAX_OPPOSITE] = vertices[topo.inc_opposite]
    return out
