"""Shadow volumes from CPU silhouettes (`CpuVolumes`): silhouettes by the multiplicity rule in
numpy (`silhouettes`), side quads uploaded per light and kept, caps drawn from the scene soup
through index lists split by triangle sign.  Why caps never shadow their own surface:
`volumes`."""

from __future__ import annotations

import moderngl
import numpy as np

from shadowvol.raster import glsl, guard
from shadowvol.raster.geometry import SceneGeometry
from shadowvol.raster.projection import in_frame, in_frame32
from shadowvol.raster.volumes.silhouettes import (
    edge_multiplicity,
    extrude_rows,
    quads_to_triangles,
    side_quads,
    topology_signs,
)
from shadowvol.raster.volumes.builder import FRONT_FACE, far_cap_pieces, runs, runs_of, set_light


class _LightVolumes:
    """One light's CPU volumes, kept while the light (and the casters) do not move: per-object
    signs, the side triangles in their own buffer, and the cap index lists once built."""

    def __init__(self):
        self.signs: list[np.ndarray] = []                         # per object
        self.sides: dict[int, tuple[int, int, int]] = {}          # object -> (first, n, repeat)
        self.side_table = np.zeros((0, 3), np.int64)  # the same, (n_objects, 3), for the draws
        self.signs_nbytes = 0
        self.corners: np.ndarray | None = None   # (n, 4) float64 world side corners (`_framed`)
        self.moves = -1                          # the geometry's `moves` the buffer is in
        # huge side triangles cut to the view's guard band (`CpuVolumes._guard_sides`): the
        # view they were cut for, the pieces' vertex ranges per object after the sides
        self.view = -1
        self.extra: dict[int, tuple[int, int]] = {}
        self.far_extra: dict[int, tuple[int, int]] = {}   # the same for huge far caps
        self.buffer: moderngl.Buffer | None = None
        self.vaos: dict[bool, moderngl.VertexArray] = {}          # clipped? -> vao
        self.caps: dict[tuple, tuple[int, int]] = {}  # (object, sign, near) -> (first, n)
        self.capped: tuple[int, ...] | None = None                # objects in the index buffer
        self.cuts = -1                                            # the geometry's cuts then
        self.index_buffer: moderngl.Buffer | None = None
        self.cap_vaos: dict[bool, moderngl.VertexArray] = {}      # near? -> vao
        # the counting programs' (`CpuVolumes.counting_programs`), made on first use:
        # ("sides", clipped?) and ("caps", near?) -> vao
        self.counting_vaos: dict[tuple[str, bool], moderngl.VertexArray] = {}
        self.frame = 0                                            # the frame it was last used in
        self.nbytes = 0   # what keeping it holds: signs (CPU), side and cap buffers (GPU)

    def count_bytes(self) -> None:
        self.nbytes = (self.signs_nbytes
                       + (0 if self.corners is None else self.corners.nbytes)
                       + sum(b.size for b in (self.buffer, self.index_buffer) if b is not None))

    def release(self) -> None:
        for obj in (*self.vaos.values(), *self.cap_vaos.values(),
                    *self.counting_vaos.values(), self.buffer, self.index_buffer):
            if obj is not None:
                obj.release()



class CpuVolumes:
    """Shadow volumes from CPU silhouettes.  Programs are made here; call `release()`.

    The volumes of the lights in use are kept (keyed by the homogeneous light): the scene's
    casters never move, so a light that comes back (every sample of an area light in every
    frame, a light in the next camera of a turntable) reuses its side quads and cap lists as
    they were uploaded.  Kept: every light of this frame and the last (`new_frame()` starts a
    frame) and the most recent others within `KEPT_OLDER_BYTES` and `KEPT_OLDER_LIGHTS` (what a
    moving light leaves behind), all within `KEPT_BYTES` of signs, side corners, side-quad and cap
    buffers.  Over the bytes the least recently used go first, but never one this frame has used: a
    frame whose lights need more (many samples of a large scene) keeps those it prepared first and
    rebuilds only the others in every frame, where plain LRU over a cycle longer than the
    cache rebuilds all.  The side corners are kept in float64 world space; when the frame
    moves (`SceneGeometry.move_to`) a kept buffer is rewritten in the new frame on its next
    `prepare`, nothing recomputed."""

    # one light holds about 3 bytes per triangle (signs, side quads) and 32 bytes per side
    # corner (float64 world, to re-frame when the eye moves): 0.72 MB a sample at 100k
    # triangles, 0.41 MB of it the corners; ~350 samples of 100k fit, and z-fail cap lists (12
    # bytes per capped triangle) for some of them.  The older lights' allowance keeps the ~100
    # lights at 100k that 32 MiB kept before the corners were kept (a rotation of a few light
    # sets, as the soft-shadow benchmark's interleaved variants are)
    KEPT_BYTES = 256 << 20
    KEPT_OLDER_BYTES = 80 << 20
    # and at most this many older lights, whatever their bytes: each also holds GL objects
    # (a buffer, its vertex arrays) that the bytes above do not count, so on a small scene a
    # moving light left ~4,000 of them, 120 MB (the rotations above need ~100)
    KEPT_OLDER_LIGHTS = 256

    def __init__(self, ctx: moderngl.Context, geometry: SceneGeometry):
        self.ctx, self.geometry = ctx, geometry
        (self.side_program, self.clip_program, self.near_program,
         self.far_program) = self._stencil = self._programs("volume.frag")
        self._counting: tuple[moderngl.Program, ...] = ()
        self.light4 = None
        self._kept: dict[bytes, _LightVolumes] = {}   # insertion order = last use
        self._current: _LightVolumes | None = None
        self._transient: _LightVolumes | None = None  # the current one when it is not kept
        self._frame = 0

    def _programs(self, fragment: str) -> tuple[moderngl.Program, ...]:
        """sides, sides clipped to the z-pass box, near caps, far caps."""
        return (glsl.program(self.ctx, "volume_side.vert", fragment),
                glsl.program(self.ctx, "volume_side.vert", fragment,
                             defines={"ZPASS_CLIP": 1}),
                glsl.program(self.ctx, "scene.vert", fragment),
                glsl.program(self.ctx, "far_cap.vert", fragment))

    @property
    def programs(self) -> tuple[moderngl.Program, ...]:
        """Every volume program (camera, light and clip uniforms go to all): the stencil's,
        then the counting ones once made."""
        return self._stencil + self._counting

    def counting_programs(self) -> tuple[moderngl.Program, ...]:
        """The same vertex stages with caster_count.frag (the ground truth's per-caster counts,
        `truth.truth_pass.CasterCounts`), made on first use, with the prepared light; the camera is
        set by the next `passes.set_camera`, which sees them in `programs`."""
        if not self._counting:
            self._counting = self._programs("caster_count.frag")
            if self.light4 is not None:
                set_light(self._counting, self.light4, self.geometry.origin)
        return self._counting

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
        set_light(self.programs, light4, self.geometry.origin)
        if self._transient is not None:   # drawn already (GL keeps a buffer its draws use)
            self._transient.release()
            self._transient = None
        key = light4.tobytes()
        kept = self._kept.pop(key, None)
        if kept is None:
            kept = self._build(light4)
        elif kept.moves != self.geometry.moves and len(kept.corners):
            kept.buffer.write(self._framed(kept.corners).tobytes())
            kept.view = -1   # huge side triangles to be cut again, in the new frame
        kept.moves = self.geometry.moves
        self._guard_sides(kept)
        kept.frame = self._frame
        kept.count_bytes()   # the guard's pieces may have grown its buffer
        self._kept[key] = kept
        self._current = kept
        self._fit()

    def _fit(self) -> None:
        """Release the least recently used volumes until the kept ones fit in KEPT_BYTES,
        sparing this frame's; if they alone do not fit, the current one is not kept (it is
        released at the next `prepare`).  Before that, of the lights used in neither this
        frame nor the last, the least recently used go until the rest fit in
        KEPT_OLDER_BYTES and number at most KEPT_OLDER_LIGHTS."""
        older = [k for k, v in self._kept.items()
                 if v.frame < self._frame - 1 and v is not self._current]
        total, left = sum(self._kept[k].nbytes for k in older), len(older)
        for key in older:   # oldest first
            if total <= self.KEPT_OLDER_BYTES and left <= self.KEPT_OLDER_LIGHTS:
                break
            old = self._kept.pop(key)
            total, left = total - old.nbytes, left - 1
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
            tris = quads_to_triangles(side_quads(topo, multiplicity // repeat, light4,
                                                 unextruded=True))   # see `_framed`
            sides.append(tris)
            out.sides[rng.index] = (n_side, len(tris), repeat)
            n_side += len(tris)
        # float32 at upload, in the frame: what GL draws; the quads were built in float64 from
        # the welded positions, which minus the origin round to the drawn vertices exactly, so
        # edges meet the caps exactly
        out.corners = np.concatenate(sides)
        out.side_table = np.array([out.sides[rng.index] for rng in self.geometry.ranges],
                                  np.int64).reshape(-1, 3)
        out.signs_nbytes = sum(s.nbytes for s in out.signs)
        data = self._framed(out.corners)
        out.buffer = self.ctx.buffer(data.tobytes() if len(data) else b"\0" * 16)
        out.vaos = {clipped: self.ctx.vertex_array(program, [(out.buffer, "4f", "in_position")])
                    for clipped, program in ((False, self.side_program),
                                             (True, self.clip_program))}
        out.count_bytes()
        return out

    def _guard_sides(self, kept: _LightVolumes) -> None:
        """Cut the side triangles that reach far outside the view to its guard band, as the
        geometry pass's huge triangles are (`guard`): GL's float32 clipping of a ground
        quad's silhouette edges 1e6 away lost their z-fail counts at the image border.  The
        part cut away meets no view ray, so every pixel's count is unchanged.  The cut
        triangles are zeroed in the buffer (GL draws nothing of them) and their pieces follow
        the side triangles (`draw_sides` draws them with their object)."""
        geometry = self.geometry
        if geometry.guard is None or kept.view == geometry.views or not len(kept.corners):
            return
        kept.view = geometry.views
        far_objects = geometry.far_objects   # only their side triangles can be huge
        if not len(far_objects) and not kept.extra and not kept.far_extra:
            return
        planes, near = geometry.guard
        far = np.concatenate([np.zeros(0, np.int64)] + [
            np.arange(kept.sides[i][0] // 3, (kept.sides[i][0] + kept.sides[i][1]) // 3)
            for i in far_objects])
        frame = in_frame(extrude_rows(kept.corners, self.light4).reshape(-1, 3, 4)[far],
                         geometry.origin)
        cut = np.isin(np.arange(len(far)), guard.huge(frame, guard.reach(frame), planes, near))
        holes = far[cut]
        if not len(holes) and not kept.extra and not len(geometry.holes) and not kept.far_extra:
            return
        data = self._framed(kept.corners).reshape(-1, 3, 4)
        data[holes] = 0.0
        # the object of every side triangle, from the per-object vertex ranges
        owner = np.zeros(len(data), np.int64)
        for i, (first, n, _) in kept.sides.items():
            owner[first // 3:(first + n) // 3] = i
        pieces, kept.extra, at = [], {}, 3 * len(data)
        for i in np.unique(owner[holes]):
            mine = [guard.cut(frame[k], planes) for k in np.flatnonzero(cut)
                    if owner[far[k]] == i]
            tris = np.concatenate(mine).reshape(-1, 4).astype(np.float32)
            pieces.append(tris)
            kept.extra[int(i)] = (at, len(tris))
            at += len(tris)
        # the far caps of the huge triangles the geometry pass cut: their projections from a
        # point light to infinity (V - L, 0), cut to the guard pyramid in homogeneous
        # coordinates, wound so that they face out of the volume with the sides' front face
        # (ccw: a sign-1 far cap is drawn cw, `FRONT_FACE`); no ties at infinity, so the
        # order of their corners is free.  `draw_caps` draws them; the index lists skip them.
        kept.far_extra = {}
        for i, tris in far_cap_pieces(geometry, self.light4, kept.signs):
            pieces.append(tris)
            kept.far_extra[i] = (at, len(tris))
            at += len(tris)
        data = np.concatenate([data.reshape(-1, 4)] + pieces)
        if data.nbytes > kept.buffer.size:
            kept.buffer.orphan(data.nbytes)
        kept.buffer.write(np.ascontiguousarray(data).tobytes())

    def _framed(self, corners: np.ndarray) -> np.ndarray:
        """(n, 4) float64 world side corners, w = 0 ones unextruded (`side_quads`) -> float32
        homogeneous in the geometry's frame.  A w = 0 corner V is extruded here as the far
        caps' shaders do it, V * L.w - L.xyz of the float32 frame V and L (exact whatever
        the order or fusion: V * 1 and V * 0 are), so that the volume is closed at infinity
        bit for bit: rounded from float64, the sides' edges there missed the far caps' and
        left slivers where a z-fail count was off by one."""
        out = np.empty(corners.shape, np.float32)
        np.subtract(corners[:, :3], self.geometry.origin, out=out[:, :3], casting="unsafe")
        out[:, 3] = corners[:, 3]
        light = in_frame32(self.light4[None], self.geometry.origin)[0]
        far = corners[:, 3] == 0.0
        out[far, :3] = out[far, :3] * light[3] - light[:3]
        return out

    def _prepare_caps(self, objects: tuple[int, ...]) -> None:
        """Upload the cap index lists (the soup vertices of the triangles of each sign) of
        `objects` for the prepared light."""
        cur = self._current
        if cur.capped == objects and cur.cuts == self.geometry.cuts:
            return
        indices, n_index = [], 0
        cur.caps.clear()
        geometry = self.geometry
        # near caps: a huge triangle's pieces in its place (`SceneGeometry.set_view`), as the
        # geometry pass drew them, for the tie; far caps: the whole triangle, whose projection
        # from the light the pieces' is not.  (The part of the near cap left out meets no view
        # ray: the counts at every pixel are those of the closed volume.)  Without huge
        # triangles both use the same lists.
        for near in (True, False) if len(geometry.holes) else (True,):
            for sign in (1, -1):   # each sign's lists one after another: one draw per sign
                for i in objects:
                    t = np.flatnonzero(cur.signs[i] == sign) + geometry.ranges[i].first
                    if near:
                        t = geometry.pieces_of(t)
                    elif len(geometry.holes):   # drawn cut (`_guard_sides`)
                        t = t[~np.isin(t, geometry.holes)]
                    idx = (3 * t[:, None] + np.arange(3)).reshape(-1)
                    indices.append(idx)
                    cur.caps[i, sign, near] = (n_index, len(idx))
                    n_index += len(idx)
        if not len(geometry.holes):
            cur.caps.update({(i, sign, False): v for (i, sign, _), v in list(cur.caps.items())})
        data = np.concatenate(indices).astype(np.int32)
        for vao in cur.cap_vaos.values():
            vao.release()
        for key in [k for k in cur.counting_vaos if k[0] == "caps"]:
            cur.counting_vaos.pop(key).release()
        if cur.index_buffer is not None:
            cur.index_buffer.release()
        cur.index_buffer = self.ctx.buffer(data.tobytes() if len(data) else b"\0" * 12)
        cur.cap_vaos = {near: self.ctx.vertex_array(
            program, self.geometry.soup_bindings(program), index_buffer=cur.index_buffer,
            index_element_size=4) for near, program in ((True, self.near_program),
                                                        (False, self.far_program))}
        cur.capped = objects
        cur.cuts = self.geometry.cuts
        cur.count_bytes()
        if cur is not self._transient:
            self._fit()

    def draw_sides(self, objects, halve: bool = False, clipped: bool = False,
                   each=None) -> None:
        """Draw the side quads of `objects`.  `clipped`: with the program that writes the
        distances to the z-pass clip box (`methods.zpass_clip_planes`; z-pass only).
        `halve`: draw the quads of casters whose multiplicities are all even once (m / 2
        copies), not twice.  Objects next to each other in the buffer are drawn by one call.
        `each(program, i)`: draw with the counting programs instead, each object alone, after
        calling `each` with the program and the object (the same quads, the same copies).

        Halving is for z-pass casters only, and only when the caller needs just "count == 0":
        the z-pass count at a pixel is linear in the multiplicities, so such a caster adds
        exactly half its count, an integer.  Where z-pass is valid (the near rectangle lies in
        none of the caster's volumes, as `methods.needs_zfail` guarantees) every caster's count
        is the number of its triangles between the point and the light, >= 0, so the sum is 0
        exactly when it was 0 before.  (The stencil's 8-bit wrap, documented in `renderer`,
        needs 256 layers either way.)  Z-fail casters must not be halved: their caps count 1
        per triangle."""
        sides = self._current.sides
        extra = self._current.extra   # pieces of huge side triangles (`_guard_sides`)
        objects = np.asarray(objects, np.int64).reshape(-1)
        if each is not None:
            vao = self._counting_vao("sides", clipped)
            for i in objects.tolist():
                spans = [s for s in (sides[i][:2], extra.get(i, (0, 0))) if s[1]]
                if spans:
                    each(vao.program, i)
                    for _ in range(1 if halve else sides[i][2]):
                        for first, count in spans:
                            vao.render(moderngl.TRIANGLES, vertices=count, first=first)
            return
        vao = self._current.vaos[clipped]
        table = self._current.side_table   # (first, n, repeat) per object, as `sides`
        # every object once, then the objects drawn twice once more: INCR_WRAP / DECR_WRAP
        # commute, so the order of the draws does not change a count
        rounds = [objects]
        if not halve:
            rounds.append(objects[table[objects, 2] == 2])
        for round_ in rounds:
            first, count = table[round_, 0], table[round_, 1]
            if extra:   # only objects far enough to have huge side triangles have pieces
                more = np.array([extra[i] for i in round_.tolist() if i in extra],
                                np.int64).reshape(-1, 2)
                first = np.concatenate([first, more[:, 0]])
                count = np.concatenate([count, more[:, 1]])
            for first_, count_ in runs_of(first, count):
                vao.render(moderngl.TRIANGLES, vertices=count_, first=first_)

    def draw_caps(self, objects, near: bool, each=None) -> None:
        """Draw the near or far caps of `objects`; `each` as in `draw_sides`."""
        if not near and self.light4[3] == 0.0:
            return  # a directional light's far cap is one point at infinity
        objects = tuple(int(i) for i in objects)
        if not objects:
            return
        self._prepare_caps(objects)
        cur = self._current
        vao = cur.cap_vaos[near] if each is None else self._counting_vao("caps", near)
        for sign in (1, -1):
            self.ctx.front_face = FRONT_FACE[near, sign]
            if each is None:
                for first, count in runs(cur.caps[i, sign, near] for i in objects):
                    vao.render(moderngl.TRIANGLES, vertices=count, first=first)
                continue
            for i in objects:
                first, count = cur.caps[i, sign, near]
                if count:
                    each(vao.program, i)
                    vao.render(moderngl.TRIANGLES, vertices=count, first=first)
        self.ctx.front_face = "ccw"
        if not near and cur.far_extra:   # huge triangles' far caps, cut (`_guard_sides`)
            if each is None:
                for first, count in runs(cur.far_extra[i] for i in objects
                                          if i in cur.far_extra):
                    cur.vaos[False].render(moderngl.TRIANGLES, vertices=count, first=first)
                return
            vao = self._counting_vao("sides", False)
            for i in (i for i in objects if i in cur.far_extra):
                each(vao.program, i)
                first, count = cur.far_extra[i]
                vao.render(moderngl.TRIANGLES, vertices=count, first=first)

    def _counting_vao(self, role: str, variant: bool) -> moderngl.VertexArray:
        """The prepared light's vao of the counting program for ("sides", clipped?) or
        ("caps", near?), made on first use (the caps' after `_prepare_caps`)."""
        cur = self._current
        key = (role, variant)
        if key not in cur.counting_vaos:
            side, clip, near, far = self.counting_programs()
            if role == "sides":
                cur.counting_vaos[key] = self.ctx.vertex_array(
                    clip if variant else side, [(cur.buffer, "4f", "in_position")])
            else:
                program = near if variant else far
                cur.counting_vaos[key] = self.ctx.vertex_array(
                    program, self.geometry.soup_bindings(program),
                    index_buffer=cur.index_buffer, index_element_size=4)
        return cur.counting_vaos[key]

    def release(self) -> None:
        for kept in (*self._kept.values(), *([self._transient] if self._transient else [])):
            kept.release()
        self._kept.clear()
        self._transient = None
        for obj in self.programs:
            obj.release()

