"""The rasterizer's ground truth (docs/CONVENTIONS.md, "Ground truth"), from the frame's own
passes: depth, normal and object id from the G-buffer's triangle key,
facing (and lit with it) from one full-screen pass over the G-buffer, casters by counting each
casting object's shadow volumes into a counter of its own.

- `depth`: the pixel-centre ray met with the key's triangle plane in float64 (`plane_depth`;
  the depth buffer's near / d only where that plane gives none); `distance` = depth × the
  length of the pixel's direction of depth 1 (from `shadowvol.cameras`' K).
- `normal`: the triangle's world-space (b − a) × (c − a), normalised in float64 (the geometry's
  own normals), negated where the G-buffer says its back face is seen, rounded to float32;
  `object_id`: the triangle's object + 1.
- `facing`: facing.frag evaluates shade.frag's n · l and cone tests once per light and writes
  the facing bits and the lit bits (facing & unshadowed) together, so that `cast = facing & ~lit`
  holds bit for bit on the raster side; the frame's `lit` is taken from that pass then.
- `casters`: after the frame, for each hard light (an area light's sample) with cast pixels,
  the objects whose box can reach them (`caster_candidates`: a box test, no per-pixel work)
  are counted each into its own counter, CASTERS_PER_GROUP at a time (`CasterCounts`): one volume pass over the group's
  volumes, the same faces, groups and depth tests as the light's stencil count, adding each
  fragment's +-1 to its caster's bit field of an integer image (caster_count.frag), then one
  pass where a counted fragment landed turning the counters into a 64-bit word of the mask
  (caster_bits.frag); one read per light and word of 64 objects.  Bit j mod 64 of word
  j div 64 is set where object j's count is not 0 and the pixel faces the light.  Counts are
  never negative where the count is exact (each is the number of the caster's triangles
  between the point and the light), so the stencil's
  count, their sum, is 0 exactly where every caster's is: `casters.any(-1)` is `cast`.  The
  cost grows with the candidates' volume fragments and the shadow's box, however many
  objects the scene holds.
"""

from __future__ import annotations

import contextlib

import moderngl
import numpy as np

from shadowvol.cameras import intrinsics, look_at_basis
from shadowvol.frame import CASTER_WORD_BITS, caster_words
from shadowvol.raster import glsl, passes, stencil
from shadowvol.raster.glsl import set_uniform
from shadowvol.raster.passes import FARTHER_THAN_NOTHING, NO_CONE
from shadowvol.raster.projection import NEARER, in_frame, top_row_first
from shadowvol.raster.target import LIGHTS_PER_PAGE
from shadowvol.raster.truth import plane_kernel
from shadowvol.scene import Camera, SpotLight

LIGHTS_PER_PASS = LIGHTS_PER_PAGE  # the frame's pages: facing and lit bits exact in a float32
CASTERS_PER_GROUP = 32  # casters of one counting pass: the slots of caster_bits.frag
# a counter field of w bits starts at 2^(w - 1) (none for 32 bits: a word of its own), so that
# a count in [-2^(w-1), 2^(w-1)) never borrows from or carries into its neighbour
FIELD_BIAS = {8: 0x80808080, 16: 0x80008000, 32: 0}
# The cast points' depths for `caster_candidates` come from the depth buffer (`cast_points`),
# within 3e-5 (relative) of the exact ones (tests/raster/test_groundtruth_vs_raytrace.py): the
# depth range is widened by 30 times that.
CAST_POINT_PAD = 1e-3
# the complement of NEARER (reversed depth: ">"): a z-fail face counts where the stencil
# pass's depth test fails, i.e. where this one passes
NOT_NEARER = "<="


class TruthPass:
    """What the ground truth needs on the GPU beside the frame: the facing program (per light
    count) and its two bit targets.  Call `release()`."""

    def __init__(self, ctx: moderngl.Context, target):
        self.ctx, self.gl = ctx, target.gl
        self.width, self.height = width, height = target.width, target.height
        # lit bits in r, facing bits in g: one read for both
        self.bits = ctx.texture((width, height), 2, dtype="f4")
        self.bits.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self.fbo = ctx.framebuffer(color_attachments=[self.bits])
        # the frame's depth (and stencil): the pass is depth-tested to the covered pixels
        target.depth_stencil.attach(self.fbo.glo)
        self._programs: dict[int, tuple] = {}
        self._bits = np.empty((height, width, 2), np.float32)
        self._casters: CasterCounts | None = None

    @property
    def casters(self) -> CasterCounts:
        """The per-caster counters, made the first time casters are asked for."""
        if self._casters is None:
            self._casters = CasterCounts(self.ctx, self.gl, self.width, self.height)
        return self._casters

    def program(self, lights: int) -> tuple:
        if lights not in self._programs:
            prog = glsl.program(self.ctx, "fullscreen.vert", "facing.frag",
                                defines={"LIGHTS": lights})
            self._programs[lights] = (prog, self.ctx.vertex_array(prog, []))
        return self._programs[lights]

    def run(self, target, geometry, lights) -> tuple[np.ndarray, np.ndarray]:
        """lit (H, W) uint32 and facing (H, W) uint32 bits of `lights` (at most
        LIGHTS_PER_PASS, bits 0..), row 0 at the top, from the G-buffer and the unshadowed bits
        the frame's volume passes left in `target`."""
        prog, vao = self.program(len(lights))
        spot = [isinstance(lt, SpotLight) for lt in lights]
        arrays = {
            "u_light": [in_frame(lt.homogeneous, geometry.origin) for lt in lights],
            "u_spot_direction": [lt.direction if s else (0.0, 0.0, 1.0)
                                 for lt, s in zip(lights, spot)],
            "u_spot_cos": [lt.cos_cutoff if s else NO_CONE for lt, s in zip(lights, spot)]}
        for name, values in arrays.items():
            set_uniform(prog, name, np.array([np.asarray(v, np.float64) for v in values],
                                             np.float32).tobytes())
        # uncovered pixels keep the clear value 0; the pass draws only where geometry is
        # (the full-screen triangle at the depth of nothing drawn, depth test "<", as the
        # shading pass), so facing.frag has no branch for them
        self.fbo.depth_mask = False
        self.fbo.color_mask = (True,) * 4
        stencil.clear_colour_attachment(self.gl, self.fbo.glo, 0, 0.0)
        self.fbo.use()
        self.ctx.enable_only(moderngl.DEPTH_TEST)
        self.ctx.depth_func = FARTHER_THAN_NOTHING
        target.position.use(1)
        target.unshadowed.use(2)
        set_uniform(prog, "u_position", 1)
        set_uniform(prog, "u_unshadowed", 2)
        geometry.triangle_data.bind_to_storage_buffer(0)
        vao.render(moderngl.TRIANGLES, vertices=3)
        self.ctx.depth_func = NEARER
        self.fbo.read_into(self._bits, components=2, attachment=0, dtype="f4")
        bits = self._bits[::-1].astype(np.uint32)   # the one flip, with the conversion
        target.use()
        return bits[..., 0], bits[..., 1]

    def release(self) -> None:
        for prog, vao in self._programs.values():
            vao.release()
            prog.release()
        self._programs.clear()
        for obj in (self.fbo, self.bits):
            obj.release()
        if self._casters is not None:
            self._casters.release()
            self._casters = None


def counter_layout(bounds) -> list[tuple[int, int, int]]:
    """(word, shift, width) of each caster's counter, for casters whose counts are at most
    `bounds` (k,) int (`overflow.detect.topology_bound`: 2 for a closed convex mesh, else its
    triangles): the narrowest of 8, 16 or 32 bits whose biased field (`FIELD_BIAS`) holds the
    bound, packed into 32-bit words in that order, one width a word (four 8-bit counters, two
    16-bit or one 32-bit)."""
    widths = [8 if b < 2**7 else 16 if b < 2**15 else 32 for b in bounds]
    out: list[tuple[int, int, int] | None] = [None] * len(widths)
    word, used = -1, 32
    for width in (8, 16, 32):
        used = 32   # a new word for each width
        for k in (k for k, w in enumerate(widths) if w == width):
            if used + width > 32:
                word, used = word + 1, 0
            out[k] = (word, used, width)
            used += width
    return out  # type: ignore[return-value]


class CasterCounts:
    """The ground truth's per-caster counters: an r32ui image array (a word of counters per
    layer, `counter_layout`), the casters' two words (rg32ui) and the pass turning one into
    the other.

    A word starts at FIELD_BIAS and ends as that plus the sum modulo 2^32 of count << shift
    over its casters, so a field reads its caster's count exactly when every count of the
    word lies in [-2^(width-1), 2^(width-1)).  Where the light's count is exact (the method
    valid for the caster, as `auto` chooses) each count is the number of the caster's
    triangles between the point and the light, 0..bound (`counter_layout`): exact.  A wrong
    count (a forced z-pass) reads exactly too while it stays in the field's range; beyond it
    the field is as wrong as the 8-bit stencil, which counts modulo 256.  Call
    `release()`."""

    def __init__(self, ctx: moderngl.Context, gl, width: int, height: int):
        self.ctx, self.gl, self.width, self.height = ctx, gl, width, height
        self.counts = None      # made by `_layers` as large as a group needs
        self.casters = ctx.texture((width, height), 2, dtype="u4")
        self.casters_fbo = ctx.framebuffer(color_attachments=[self.casters])
        self._bits: dict[int, tuple] = {}   # counter words -> caster_bits program, vao

    def _layers(self, words: int) -> None:
        """At least `words` layers of counters."""
        if self.counts is not None and self.counts.size[2] >= words:
            return
        if self.counts is not None:
            self.counts.release()
        self.counts = self.ctx.texture_array((self.width, self.height, words), 1, dtype="u4")

    def clear_casters(self, box: tuple[int, int, int, int]) -> None:
        """The casters' words to 0 in `box` (x, y, w, h, GL's rows)."""
        stencil.clear_uint_texture(self.gl, self.casters.glo, box, components=2)

    def _clear_counts(self, layout, box: tuple[int, int, int, int]) -> None:
        """Each counter word of `layout` to its FIELD_BIAS in `box`."""
        width = {word: bits for word, _, bits in layout}
        for word, bits in width.items():
            stencil.clear_uint_texture(self.gl, self.counts.glo, box,
                                          value=FIELD_BIAS[bits], layer=word)

    def count(self, pipe, choice: np.ndarray, group: list[int],
              layout: list[tuple[int, int, int]], halve: bool, clip_planes,
              box: tuple[int, int, int, int]) -> None:
        """Counter k := object group[k]'s own count, in its field of `layout`
        (`counter_layout`; at most CASTERS_PER_GROUP objects), and the stencil := 1 where any
        counted fragment lands, else 0, in `box` (the scissor must be set to it): the light's
        volume count
        (`passes.count_each_caster`, the same `choice`, `halve` and `clip_planes` as
        `passes.count_signed`) with the counting programs, z-fail groups under the
        complementary depth test.  `pipe.volumes` must be prepared for the light and its
        `counting_programs` made before the frame's `passes.set_camera`."""
        ctx, gl = self.ctx, self.gl
        programs = pipe.volumes.counting_programs()
        field = dict(zip(group, layout))

        def each(program, j):
            word, shift, _ = field[j]
            set_uniform(program, "u_word", word)
            set_uniform(program, "u_shift", shift)

        @contextlib.contextmanager
        def counting(zfail_group: bool, depth_clamp: bool):
            for p in programs:
                set_uniform(p, "u_front_step", -1 if zfail_group else 1)
            ctx.depth_func = NOT_NEARER if zfail_group else NEARER
            try:
                with stencil.caster_touching(gl, depth_clamp):
                    yield
            finally:
                ctx.depth_func = NEARER

        self._layers(1 + max(word for word, _, _ in layout))
        self._clear_counts(layout, box)
        pipe.target.clear_stencil()   # within the scissor
        self.counts.bind_to_image(0, read=True, write=True)
        passes.count_each_caster(pipe, choice, objects=group, each=each, counting=counting,
                                 halve=halve, clip_planes=clip_planes)
        ctx.memory_barrier()   # the counts, before anything reads them

    def add_bits(self, target, group: list[int], layout: list[tuple[int, int, int]]) -> None:
        """caster_bits.frag over target.fbo (its scissor applies): the casters' words get the
        bit of group[k] where its counter is not 0.  Drawn only where `count` left the
        stencil 1 (a counter that no fragment reached is 0)."""
        ctx = self.ctx
        words = 1 + max(w for w, _, _ in layout)
        if words not in self._bits:
            program = glsl.program(ctx, "fullscreen.vert", "caster_bits.frag",
                                   defines={"WORDS": words})
            self._bits[words] = (program, ctx.vertex_array(program, []))
        program, vao = self._bits[words]
        width = np.zeros(words, np.int32)
        first_slot = np.zeros(words, np.int32)
        object_bits = np.zeros((CASTERS_PER_GROUP, 2), np.uint32)
        slot = 0
        for w in range(words):   # the slots of word w: its fields, in order
            fields = sorted((s, b, j) for (w_, s, b), j in zip(layout, group) if w_ == w)
            width[w], first_slot[w] = fields[0][1], slot
            for _, _, j in fields:
                bit = j % CASTER_WORD_BITS   # the group's objects share a word
                object_bits[slot, bit // 32] = 1 << (bit % 32)
                slot += 1
        set_uniform(program, "u_width", width.tobytes())
        set_uniform(program, "u_first_slot", first_slot.tobytes())
        set_uniform(program, "u_object_bits", object_bits.tobytes())
        self.counts.bind_to_image(0, read=True, write=False)
        self.casters.bind_to_image(1, read=True, write=True)
        target.use(colour=False, depth=False)
        ctx.enable_only(moderngl.NOTHING)
        with stencil.where_shadowed(self.gl):
            vao.render(moderngl.TRIANGLES, vertices=3)
        ctx.enable_only(moderngl.DEPTH_TEST)
        ctx.memory_barrier()   # the casters' words, before they are read or added to

    def read_casters(self, box: tuple[int, int, int, int], objects: int) -> np.ndarray:
        """(h, w) uint64 of the casters' 64-bit word in `box` (x, y, w, h, GL's rows), row 0
        at the top (a view); its low half only when the word's `objects` are at most 32."""
        words = np.zeros((box[3], box[2], 2), np.uint32)
        components = 1 if objects <= 32 else 2
        staging = words if components == 2 else np.empty((box[3], box[2]), np.uint32)
        self.casters_fbo.read_into(staging, viewport=box, components=components,
                                   attachment=0, dtype="u4")
        if components == 1:
            words[..., 0] = staging
        # little-endian: word 0 holds bits 0-31
        return top_row_first(words.view("<u8")[..., 0])

    def read_counts(self, layout: list[tuple[int, int, int]]) -> np.ndarray:
        """(k, H, W) int64: the counters of `layout` as `count` left them, decoded, row 0 at
        the top (for tests: a frame reads only the casters' words)."""
        words = np.frombuffer(self.counts.read(), np.uint32).reshape(
            self.counts.size[2], self.height, self.width)[:, ::-1].astype(np.int64)
        out = []
        for w, s, b in layout:
            field = (words[w] >> s) & ((1 << b) - 1)
            out.append(field - (1 << (b - 1)) if b < 32 else field - ((field >> 31) << 32))
        return np.stack(out)

    def release(self) -> None:
        for program, vao in self._bits.values():
            vao.release()
            program.release()
        self._bits.clear()
        for obj in (self.casters_fbo, self.casters, self.counts):
            if obj is not None:
                obj.release()


def read_surface(target, covered: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The G-buffer where `covered` (H, W) bool: triangle (H, W) int64 (−1 elsewhere) and
    front (H, W) bool (its front face is seen), row 0 at the top.  Only covered pixels are
    read: the geometry pass writes the G-buffer only where it draws (it is not cleared), so
    elsewhere it may hold an earlier frame's surfaces.  Only the key channel is flipped (its
    `np.where` makes the one copy; the positions, channels 0-2, are not returned)."""
    raw = np.empty((target.height, target.width, 4), np.float32)
    target.gbuffer_fbo.read_into(raw, components=4, attachment=0, dtype="f4")
    key = np.where(covered, raw[::-1, :, 3], 0.0).astype(np.int64)   # top_row_first's flip
    return np.abs(key) - 1, key > 0


def read_depth(target) -> np.ndarray:
    """(H, W) float32: the depth buffer as stored (near / eye-space depth; 0, the clear value,
    where nothing is drawn), row 0 at the top."""
    return top_row_first(stencil.read_depth(target.gl, target.gbuffer_fbo.glo,
                                               target.width, target.height))


def eye_depth(stored: np.ndarray, camera: Camera) -> np.ndarray:
    """(H, W) float32 eye-space depth of `read_depth`'s values: near / stored, in float64 and
    rounded once; inf where nothing is drawn."""
    with np.errstate(divide="ignore"):
        return (np.float64(camera.near) / stored.astype(np.float64)).astype(np.float32)


def ray_lengths(camera: Camera, width: int, height: int) -> np.ndarray:
    """(H, W) float64: the length of each pixel centre's direction of eye-space depth 1."""
    K = intrinsics(camera, width, height)
    x = (np.arange(width) + 0.5 - K[0, 2]) / K[0, 0]
    y = (np.arange(height) + 0.5 - K[1, 2]) / K[1, 1]
    return np.sqrt(1.0 + x[None, :] ** 2 + y[:, None] ** 2)


def surface_outputs(geometry, triangle: np.ndarray, front: np.ndarray, want: set[str]
                    ) -> dict[str, np.ndarray]:
    """normal (H, W, 3) float32 and object_id (H, W) uint16, as asked, from the G-buffer's
    triangle key."""
    out = {}
    if plane_kernel.surface is not None:   # the same values in one compiled pass
        h, w = triangle.shape
        normal = np.empty((h, w, 3), np.float32)
        ids = np.empty((h, w), np.uint16)
        plane_kernel.surface(np.ascontiguousarray(triangle, np.int64).reshape(-1),
                             np.ascontiguousarray(front).reshape(-1),
                             np.ascontiguousarray(geometry.face_normals32),
                             np.ascontiguousarray(geometry.triangle_objects),
                             normal.reshape(-1, 3), ids.reshape(-1),
                             "normal" in want, "object_id" in want)
        if "normal" in want:
            out["normal"] = normal
        if "object_id" in want:
            out["object_id"] = ids
        return out
    hit = triangle >= 0
    t = np.where(hit, triangle, 0)
    if "normal" in want:
        # rounded to float32 first: negation and the zero fill are exact either way
        n = geometry.face_normals32[t]
        np.negative(n, out=n, where=~front[..., None])
        n[~hit] = 0.0
        out["normal"] = n
    if "object_id" in want:
        ids = geometry.triangle_objects[t] + 1
        out["object_id"] = np.where(hit, ids, 0).astype(np.uint16)
    return out


def cast_points(camera: Camera, stored: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(8, 3) float64: the corners of a frustum piece holding the world points of the pixels
    of `mask` (H, W) bool (not empty): the box of those pixels (their whole squares) between
    the nearest and the farthest of their eye-space depths, from `stored` (H, W) float32 (the
    depth buffer, `read_depth`), the near face moved CAST_POINT_PAD of its depth toward the
    eye and the far face as much away.  Convex, so the box of its corners holds every point
    (no G-buffer read, no per-pixel unprojection: the depth is read for the ground truth
    anyway)."""
    h, w = stored.shape
    K = intrinsics(camera, w, h)
    rows, cols = cast_box(mask)
    values = stored[rows, cols][mask[rows, cols]].astype(np.float64)
    z_near, z_far = camera.near / values.max(), camera.near / values.min()
    right, up, back = look_at_basis(camera)
    corners = []
    for z in (z_near * (1.0 - CAST_POINT_PAD), z_far * (1.0 + CAST_POINT_PAD)):
        for u in (cols.start, cols.stop):
            for v in (rows.start, rows.stop):
                # OpenCV camera coordinates (x right, y down, z forward) of the pixel corner
                x, y = (u - K[0, 2]) / K[0, 0] * z, (v - K[1, 2]) / K[1, 1] * z
                corners.append(camera.eye + x * right - y * up - z * back)
    return np.array(corners)


def caster_candidates(bounds: np.ndarray, points: np.ndarray, light4: np.ndarray) -> list[int]:
    """The objects whose box (bounds (n, 2, 3) float64) can lie between some of `points`
    (k, 3) float32 or float64 (the cast pixels' world positions, or the corners of a box
    around them: `cast_points`) and the light (4,)
    homogeneous: the box of the points joined with a point light's position, or swept toward
    a directional light (to infinity), meets the object's box.  Conservative (boxes padded by 1e-6 of their size):
    a candidate may cast nothing, a caster is never missed."""
    # the box of the points (float32 world positions are exact in float64)
    lo = points.min(axis=0).astype(np.float64)
    hi = points.max(axis=0).astype(np.float64)
    pad = 1e-6 * (np.abs(bounds).max() + max(np.abs(lo).max(), np.abs(hi).max()) + 1.0)
    o_lo, o_hi = bounds[:, 0] - pad, bounds[:, 1] + pad
    if light4[3] != 0.0:
        position = light4[:3] / light4[3]
        lo, hi = np.minimum(lo, position), np.maximum(hi, position)
        meets = ((o_lo <= hi) & (o_hi >= lo)).all(axis=1)
        return [int(j) for j in np.flatnonzero(meets)]
    # the box [lo, hi] moved by s·u, s >= 0, toward the light: per axis an interval of s
    u = light4[:3]
    s_lo = np.zeros(len(bounds))
    s_hi = np.full(len(bounds), np.inf)
    meets = np.ones(len(bounds), bool)
    for k in range(3):
        if u[k] == 0.0:
            meets &= (o_lo[:, k] <= hi[k]) & (o_hi[:, k] >= lo[k])
            continue
        a = (o_lo[:, k] - hi[k]) / u[k]
        b = (o_hi[:, k] - lo[k]) / u[k]
        s_lo = np.maximum(s_lo, np.minimum(a, b))
        s_hi = np.minimum(s_hi, np.maximum(a, b))
    meets &= s_lo <= s_hi
    return [int(j) for j in np.flatnonzero(meets)]


def count_casters(pipe, counter: CasterCounts, choice: np.ndarray, candidates: list[int],
                  bounds: np.ndarray, where: np.ndarray, halve: bool,
                  clip_planes) -> np.ndarray:
    """(H, W, K) uint64, K = `caster_words(n_objects)`: bit j mod 64 of word j div 64
    where candidate object j's own shadow volumes count non-zero and `where` (H, W) bool (the
    pixels facing the light).  bounds (n_objects,) int: each object's
    `overflow.detect.topology_bound`.  `pipe` (its volumes prepared for the light),
    `choice`, `halve` and `clip_planes` as `CasterCounts.count` takes them.

    The candidates go word by word (objects 64k .. 64k + 63), each word's in groups of
    CASTERS_PER_GROUP: one counting pass and one bits pass a group, one read a word (a word
    without candidates costs nothing).  Everything is drawn (scissor), cleared and read only
    in the box of the cast pixels (`cast_box`).  Leaves the stencil holding the last group's
    count."""
    bits = np.zeros(where.shape + (caster_words(len(bounds)),), np.uint64)
    target = pipe.target
    if not candidates:
        return bits
    rows, cols = cast_box(where)
    box = (cols.start, target.height - rows.stop, cols.stop - cols.start,
           rows.stop - rows.start)  # GL counts rows from the bottom
    words: dict[int, list[int]] = {}
    for j in candidates:
        words.setdefault(j // CASTER_WORD_BITS, []).append(j)
    # moderngl keeps a scissor per framebuffer and applies it when the framebuffer is bound;
    # both passes draw into target.fbo
    target.fbo.scissor = box
    try:
        for word, in_word in words.items():
            target.use()
            counter.clear_casters(box)
            for first in range(0, len(in_word), CASTERS_PER_GROUP):
                group = in_word[first:first + CASTERS_PER_GROUP]
                layout = counter_layout(bounds[group])
                counter.count(pipe, choice, group, layout, halve, clip_planes, box)
                counter.add_bits(target, group, layout)
            combined = counter.read_casters(box, 1 + max(in_word) % CASTER_WORD_BITS)
            bits[rows, cols, word] = np.where(where[rows, cols], combined, np.uint64(0))
    finally:
        target.fbo.scissor = None
        target.use()  # re-applies the framebuffer's state: no scissor
    return bits


def cast_box(mask: np.ndarray) -> tuple[slice, slice]:
    """The rows and columns (top-first) of the smallest box around the True pixels of `mask`
    (H, W) bool (the whole frame when it has none)."""
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if len(rows) == 0:
        return slice(0, mask.shape[0]), slice(0, mask.shape[1])
    return slice(int(rows[0]), int(rows[-1]) + 1), slice(int(cols[0]), int(cols[-1]) + 1)

