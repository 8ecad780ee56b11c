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


class _LightVolumes:
    """One light's CPU volumes, kept while the light (and the casters) do not move: per-object
    signs, the side triangles in their own buffer, and the cap index lists once built."""

    def __init__(self):
        self.signs: list[np.ndarray] = []                         # per object
        self.sides: dict[int, tuple[int, int, int]] = {}          # object -> (first, n, repeat)
        self.buffer: moderngl.Buffer | None = None
        self.vaos: dict[bool, moderngl.VertexArray] = {}          # clipped? -> vao
        self.caps: dict[tuple[int, int], tuple[int, int]] = {}    # (object, sign) -> (first, n)
        self.capped: tuple[int, ...] | None = None                # objects in the index buffer
        self.index_buffer: moderngl.Buffer | None = None
        self.cap_vaos: dict[bool, moderngl.VertexArray] = {}      # near? -> vao
        self.frame = 0                                            # the frame it was last used in
        self.nbytes = 0   # what keeping it holds: signs (CPU), side and cap buffers (GPU)

    def count_bytes(self) -> None:
        self.nbytes = (sum(s.nbytes for s in self.signs)
                       + sum(b.size for b in (self.buffer, self.index_buffer) if b is not None))

    def release(self) -> None:
        for obj in (*self.vaos.values(), *self.cap_vaos.values(), self.buffer,
                    self.index_buffer):
            if obj is not None:
                obj.release()


class CpuVolumes:
    """Shadow volumes from CPU silhouettes.  Programs are made here; call `release()`.

    The volumes of the lights in use are kept (keyed by the homogeneous light): the scene's
    casters never move, so a light that comes back (every sample of an area light in every
    frame, a light in the next camera of a turntable) reuses its side quads and cap lists as
    they were uploaded.  Kept: every light of this frame and the last (`new_frame()` starts a
    frame) and the most recent others within `KEPT_OLDER_BYTES` (what a moving light leaves
    behind), all within `KEPT_BYTES` of signs, side-quad and cap buffers.  Over the bytes the
    least recently used go first, but never one this frame has used: a frame whose lights need
    more (many samples of a large scene) keeps those it prepared first and rebuilds only the
    others in every frame, where plain LRU over a cycle longer than the cache rebuilds all."""

    # one light holds about 3 bytes per triangle (signs, side quads); 64 samples of a million
    # triangles fit, and z-fail cap lists (12 bytes per capped triangle) for some of them
    KEPT_BYTES = 256 << 20
    KEPT_OLDER_BYTES = 32 << 20

    def __init__(self, ctx: moderngl.Context, geometry: SceneGeometry):
        self.ctx, self.geometry = ctx, geometry
        self.side_program = glsl.program(ctx, "volume_side.vert", "volume.frag")
        self.clip_program = glsl.program(ctx, "volume_side.vert", "volume.frag",
                                         defines={"ZPASS_CLIP": 1})
        self.near_program = glsl.program(ctx, "scene.vert", "volume.frag")
        self.far_program = glsl.program(ctx, "far_cap.vert", "volume.frag")
        self.programs = (self.side_program, self.clip_program, self.near_program,
                         self.far_program)
        self.light4 = None
        self._kept: dict[bytes, _LightVolumes] = {}   # insertion order = last use
        self._current: _LightVolumes | None = None
        self._transient: _LightVolumes | None = None  # the current one when it is not kept
        self._frame = 0

    @property
    def _signs(self) -> list[np.ndarray]:
        return self._current.signs

    @property
    def _sides(self) -> dict[int, tuple[int, int, int]]:
        return self._current.sides

    def new_frame(self) -> None:
        """A frame begins: the volumes it prepares are kept before any earlier frame's."""
        self._frame += 1

    def prepare(self, light4: np.ndarray) -> None:
        """Select this light's side quads, computing and uploading them unless they are kept.
        Cap index lists are built on the first `draw_caps` (most frames z-fail few casters or
        none, and a cap list is 3 indices per triangle).  Sets the light on the volume
        programs."""
        light4 = np.asarray(light4, np.float64)
        self.light4 = light4
        _set_light(self.programs, light4)
        if self._transient is not None:   # drawn already (GL keeps a buffer its draws use)
            self._transient.release()
            self._transient = None
        key = light4.tobytes()
        kept = self._kept.pop(key, None)
        if kept is None:
            kept = self._build(light4)
        kept.frame = self._frame
        self._kept[key] = kept
        self._current = kept
        self._fit()

    def _fit(self) -> None:
        """Release the least recently used volumes until the kept ones fit in KEPT_BYTES,
        sparing this frame's; if they alone do not fit, the current one is not kept (it is
        released at the next `prepare`).  Before that, of the lights used in neither this
        frame nor the last, the least recently used go until the rest fit in
        KEPT_OLDER_BYTES."""
        older = [k for k, v in self._kept.items()
                 if v.frame < self._frame - 1 and v is not self._current]
        total = sum(self._kept[k].nbytes for k in older)
        for key in older:   # oldest first
            if total <= self.KEPT_OLDER_BYTES:
                break
            old = self._kept.pop(key)
            total -= old.nbytes
            old.release()
        total = sum(v.nbytes for v in self._kept.values())
        for key in list(self._kept):   # oldest first; this frame's come last
            if total <= self.KEPT_BYTES:
                return
            old = self._kept[key]
            if old.frame == self._frame or old is self._current:
                break
            total -= old.nbytes
            del self._kept[key]
            old.release()
        if total > self.KEPT_BYTES:
            key = next(reversed(self._kept))   # the current one: the last prepared
            self._transient = self._kept.pop(key)

    def _build(self, light4: np.ndarray) -> _LightVolumes:
        out = _LightVolumes()
        sides, n_side = [], 0
        for rng, topo in zip(self.geometry.ranges, self.geometry.topologies):
            signs = topology_signs(topo, light4)
            out.signs.append(signs)
            multiplicity = edge_multiplicity(topo, signs)
            # A caster whose multiplicities are all even (a closed, consistently wound mesh
            # gives 2 on every silhouette edge) stores each quad once, m / 2 copies, and is
            # drawn twice: the same quads as |m| copies, in another order, and stencil
            # INCR_WRAP / DECR_WRAP commute.  See `draw_sides` for drawing it once.
            repeat = 2 if multiplicity.any() and not (multiplicity & 1).any() else 1
            tris = quads_to_triangles(side_quads(topo, multiplicity // repeat, light4))
            sides.append(tris)
            out.sides[rng.index] = (n_side, len(tris), repeat)
            n_side += len(tris)
        # float32 at upload: what GL draws; the quads were built in float64 from the welded
        # positions, which are the drawn vertices exactly, so edges meet the caps exactly
        data = np.concatenate(sides).astype(np.float32)
        out.buffer = self.ctx.buffer(data.tobytes() if len(data) else b"\0" * 16)
        out.vaos = {clipped: self.ctx.vertex_array(program, [(out.buffer, "4f", "in_position")])
                    for clipped, program in ((False, self.side_program),
                                             (True, self.clip_program))}
        out.count_bytes()
        return out

    def _prepare_caps(self, objects: tuple[int, ...]) -> None:
        """Upload the cap index lists (the soup vertices of the triangles of each sign) of
        `objects` for the prepared light."""
        cur = self._current
        if cur.capped == objects:
            return
        indices, n_index = [], 0
        cur.caps.clear()
        for sign in (1, -1):   # each sign's lists one after another: one draw per sign
            for i in objects:
                rng = self.geometry.ranges[i]
                t = np.flatnonzero(cur.signs[i] == sign) + rng.first
                idx = (3 * t[:, None] + np.arange(3)).reshape(-1)
                indices.append(idx)
                cur.caps[i, sign] = (n_index, len(idx))
                n_index += len(idx)
        data = np.concatenate(indices).astype(np.int32)
        for vao in cur.cap_vaos.values():
            vao.release()
        if cur.index_buffer is not None:
            cur.index_buffer.release()
        cur.index_buffer = self.ctx.buffer(data.tobytes() if len(data) else b"\0" * 12)
        cur.cap_vaos = {near: self.ctx.vertex_array(
            program, self.geometry.soup_bindings(program), index_buffer=cur.index_buffer,
            index_element_size=4) for near, program in ((True, self.near_program),
                                                        (False, self.far_program))}
        cur.capped = objects
        cur.count_bytes()
        if cur is not self._transient:
            self._fit()

    def draw_sides(self, objects, halve: bool = False, clipped: bool = False) -> None:
        """Draw the side quads of `objects`.  `clipped`: with the program that writes the
        distances to the z-pass clip box (`methods.zpass_clip_planes`; z-pass only).
        `halve`: draw the quads of casters whose multiplicities are all even once (m / 2
        copies), not twice.  Objects next to each other in the buffer are drawn by one call.

        Halving is for z-pass casters only, and only when the caller needs just "count == 0":
        the z-pass count at a pixel is linear in the multiplicities, so such a caster adds
        exactly half its count, an integer.  Where z-pass is valid (the near rectangle lies in
        none of the caster's volumes, as `methods.needs_zfail` guarantees) every caster's count
        is the number of its triangles between the point and the light, >= 0, so the sum is 0
        exactly when it was 0 before.  (The stencil's 8-bit wrap, documented in `renderer`,
        needs 256 layers either way.)  Z-fail casters must not be halved: their caps count 1
        per triangle."""
        vao = self._current.vaos[clipped]
        sides = self._current.sides
        # every object once, then the objects drawn twice once more: INCR_WRAP / DECR_WRAP
        # commute, so the order of the draws does not change a count
        rounds = [list(objects)]
        if not halve:
            rounds.append([i for i in objects if sides[i][2] == 2])
        for round_ in rounds:
            for first, count in _runs(sides[i][:2] for i in round_):
                vao.render(moderngl.TRIANGLES, vertices=count, first=first)

    def draw_caps(self, objects, near: bool) -> None:
        if not near and self.light4[3] == 0.0:
            return  # a directional light's far cap is one point at infinity
        objects = tuple(int(i) for i in objects)
        if not objects:
            return
        self._prepare_caps(objects)
        cur = self._current
        vao = cur.cap_vaos[near]
        for sign in (1, -1):
            self.ctx.front_face = _FRONT_FACE[near, sign]
            for first, count in _runs(cur.caps[i, sign] for i in objects):
                vao.render(moderngl.TRIANGLES, vertices=count, first=first)
        self.ctx.front_face = "ccw"

    def release(self) -> None:
        for kept in (*self._kept.values(), *([self._transient] if self._transient else [])):
            kept.release()
        self._kept.clear()
        self._transient = None
        for obj in self.programs:
            obj.release()


def _runs(ranges) -> list[tuple[int, int]]:
    """(first, count) ranges, empty ones dropped and ranges that continue each other merged:
    one draw call per run instead of one per object."""
    out: list[list[int]] = []
    for first, count in ranges:
        if not count:
            continue
        if out and out[-1][0] + out[-1][1] == first:
            out[-1][1] += count
        else:
            out.append([first, count])
    return [(f, c) for f, c in out]


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

    def new_frame(self) -> None:
        """Nothing is kept per light (the common interface)."""

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


def _set_light(programs, light4: np.ndarray) -> None:
    """The one place `u_light` of the volume programs is set: by the builder that holds it."""
    for p in programs:
        glsl.set_uniform(p, "u_light", tuple(float(x) for x in light4))
