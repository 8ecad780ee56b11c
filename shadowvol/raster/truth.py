"""The rasterizer's ground truth (docs/CONVENTIONS.md, "Ground truth"), from the frame's own
passes: depth from the depth buffer, normal and object id from the G-buffer's triangle key,
facing (and lit with it) from one full-screen pass over the G-buffer, casters by counting each
casting object's shadow volumes alone.

- `depth`: the reversed infinite projection stores near / d (`projection`), so d = near / stored,
  exact to float32 rounding of that projection; `distance` = depth × the length of the pixel's
  direction of depth 1 (from `shadowvol.cameras`' K).
- `normal`: the triangle's world-space (b − a) × (c − a), normalised in float64 (the geometry's
  own normals), negated where the G-buffer says its back face is seen, rounded to float32;
  `object_id`: the triangle's object + 1.
- `facing`: facing.frag evaluates shade.frag's n · l and cone tests once per light and writes
  the facing bits and the lit bits (facing & unshadowed) together, so that `cast = facing & ~lit`
  holds bit for bit on the raster side; the frame's `lit` is taken from that pass then.
- `casters`: after the frame, for each light with cast pixels, the objects whose box can reach
  them (`caster_candidates`: a box test, no per-pixel work) are counted one at a time (the
  light's volume pass restricted to that object, the same method) and their stencil read back:
  bit j where object j's count is not 0 and the pixel faces the light.  Counts are never
  negative (each is the number of the caster's triangles between the point and the light), so
  the union count is 0 exactly where every object's is: `casters != 0` is `cast`.  The cost is
  one volume pass and one stencil read per candidate, however many objects the scene holds.
"""

from __future__ import annotations

import moderngl
import numpy as np

from shadowvol.cameras import intrinsics
from shadowvol.io import GROUND_TRUTH
from shadowvol.raster import glsl, passes
from shadowvol.raster import stencil as stencil_gl
from shadowvol.raster.glsl import set_uniform
from shadowvol.raster.passes import NO_CONE
from shadowvol.raster.projection import in_frame, top_row_first
from shadowvol.raster.target import LIGHTS_PER_PAGE
from shadowvol.scene import Camera, SpotLight

TRUTH_OUTPUTS = GROUND_TRUTH  # the names of docs/CONVENTIONS.md, one list for both renderers
MAX_CASTERS = 64
LIGHTS_PER_PASS = LIGHTS_PER_PAGE  # the frame's pages: facing and lit bits exact in a float32


class TruthPass:
    """What the ground truth needs on the GPU beside the frame: the facing program (per light
    count) and its two bit targets.  Call `release()`."""

    def __init__(self, ctx: moderngl.Context, target):
        self.ctx = ctx
        self.width, self.height = width, height = target.width, target.height
        self.lit = ctx.texture((width, height), 1, dtype="f4")
        self.facing = ctx.texture((width, height), 1, dtype="f4")
        self.casters = ctx.texture((width, height), 4, dtype="f4")
        for t in (self.lit, self.facing, self.casters):
            t.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self.fbo = ctx.framebuffer(color_attachments=[self.lit, self.facing])
        # the casters' marks are stencil-tested against the frame's own depth-stencil buffer
        self.casters_fbo = ctx.framebuffer(color_attachments=[self.casters])
        target.depth_stencil.attach(self.casters_fbo.glo)
        self.mark = glsl.program(ctx, "fullscreen.vert", "caster_bit.frag")
        self.mark_vao = ctx.vertex_array(self.mark, [])
        self._programs: dict[int, tuple] = {}
        self._bits = np.empty((height, width), np.float32)

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
        self.fbo.use()
        self.ctx.enable_only(moderngl.NOTHING)
        target.position.use(1)
        target.unshadowed.use(2)
        set_uniform(prog, "u_position", 1)
        set_uniform(prog, "u_unshadowed", 2)
        geometry.triangle_data.bind_to_storage_buffer(0)
        vao.render(moderngl.TRIANGLES, vertices=3)
        self.ctx.enable_only(moderngl.DEPTH_TEST)
        out = []
        for attachment in (0, 1):
            self.fbo.read_into(self._bits, components=1, attachment=attachment, dtype="f4")
            out.append(top_row_first(self._bits).astype(np.uint32))
        target.use()
        return out[0], out[1]

    def release(self) -> None:
        for prog, vao in self._programs.values():
            vao.release()
            prog.release()
        self._programs.clear()
        for obj in (self.mark_vao, self.mark, self.casters_fbo, self.fbo, self.lit, self.facing,
                    self.casters):
            obj.release()


def read_surface(target, covered: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The G-buffer where `covered` (H, W) bool: triangle (H, W) int64 (−1 elsewhere), front
    (H, W) bool (its front face is seen) and world (H, W, 3) float32 positions, row 0 at the
    top.  Only covered pixels are read: the geometry pass writes the G-buffer only where it
    draws (it is not cleared), so elsewhere it may hold an earlier frame's surfaces."""
    raw = np.empty((target.height, target.width, 4), np.float32)
    target.gbuffer_fbo.read_into(raw, components=4, attachment=0, dtype="f4")
    raw = top_row_first(raw)
    key = np.where(covered, raw[..., 3], 0.0).astype(np.int64)
    return np.abs(key) - 1, key > 0, raw[..., :3]


def read_depth(target, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """(H, W) float32 eye-space depth from the depth buffer (near / stored), inf where nothing
    is drawn (stored 0, the clear value), and covered (H, W) bool (stored > 0), row 0 at the
    top."""
    stored = top_row_first(stencil_gl.read_depth(target.gl, target.gbuffer_fbo.glo,
                                                 target.width, target.height))
    with np.errstate(divide="ignore"):
        depth = (np.float64(camera.near) / stored.astype(np.float64)).astype(np.float32)
    return depth, stored > 0


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


def caster_candidates(bounds: np.ndarray, points: np.ndarray, light4: np.ndarray) -> list[int]:
    """The objects whose box (bounds (n, 2, 3) float64) can lie between some of `points`
    (k, 3) float32 or float64 (the cast pixels' world positions) and the light (4,)
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


def count_casters(ctx, gl, target, truth_pass: TruthPass, volumes, choice: np.ndarray,
                  candidates: list[int], where: np.ndarray, halve: bool, clip_planes
                  ) -> np.ndarray:
    """(H, W) uint64: bit j where candidate object j's own shadow volumes count non-zero and
    `where` (H, W) bool (the pixels facing the light).  `volumes` must be prepared for the
    light; `choice` (n_objects,) bool is the light's z-fail choice per caster.

    Per candidate: its volume count (the stencil), then caster_bit.frag adds its bit where the
    count is not 0; one read of the sums at the end.  Everything is drawn (scissor) and read
    only in the box of the cast pixels (`cast_box`)."""
    bits = np.zeros(where.shape, np.uint64)
    rows, cols = cast_box(where)
    h, w = rows.stop - rows.start, cols.stop - cols.start
    box = (cols.start, target.height - rows.stop, w, h)  # GL counts rows from the bottom
    marks = truth_pass.casters_fbo
    # moderngl keeps a scissor per framebuffer and applies it when the framebuffer is bound;
    # the volume passes draw into target.fbo (count_volumes binds it)
    target.fbo.scissor = marks.scissor = box
    try:
        marks.use()
        marks.clear(0.0, 0.0, 0.0, 0.0)  # (within the scissor)
        for j in candidates:
            passes.count_volumes(ctx, gl, target, volumes, choice, halve=halve,
                                 clip_planes=clip_planes, objects=[j])
            marks.depth_mask = False
            marks.use()
            ctx.enable_only(moderngl.BLEND)
            ctx.blend_func = moderngl.ONE, moderngl.ONE
            ctx.blend_equation = moderngl.FUNC_ADD
            bit = [0.0] * 4
            bit[j // 16] = float(2 ** (j % 16))
            set_uniform(truth_pass.mark, "u_bit", tuple(bit))
            with stencil_gl.where_shadowed(gl):
                truth_pass.mark_vao.render(moderngl.TRIANGLES, vertices=3)
            ctx.enable_only(moderngl.DEPTH_TEST)
        sums = np.empty((h, w, 4), np.float32)
        marks.read_into(sums, viewport=box, components=4, attachment=0, dtype="f4")
    finally:
        target.fbo.scissor = marks.scissor = None
        target.use()  # re-applies the framebuffer's state: no scissor
    words = top_row_first(sums).astype(np.uint64)
    combined = (words[..., 0] | (words[..., 1] << np.uint64(16))
                | (words[..., 2] << np.uint64(32)) | (words[..., 3] << np.uint64(48)))
    bits[rows, cols] = np.where(where[rows, cols], combined, np.uint64(0))
    return bits


def cast_box(mask: np.ndarray) -> tuple[slice, slice]:
    """The rows and columns (top-first) of the smallest box around the True pixels of `mask`
    (H, W) bool (the whole frame when it has none)."""
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if len(rows) == 0:
        return slice(0, mask.shape[0]), slice(0, mask.shape[1])
    return slice(int(rows[0]), int(rows[-1]) + 1), slice(int(cols[0]), int(cols[-1]) + 1)


def check_casters(objects: int) -> None:
    if objects > MAX_CASTERS:
        from shadowvol.scene import SceneError

        raise SceneError("objects", f"casters is a {MAX_CASTERS}-bit mask, and this scene has "
                                    f"{objects} objects; ask for the other outputs, or split "
                                    "the scene")

