"""The passes of a shadowed frame (deferred: the scene's triangles are drawn once), in order:

1. `geometry_pass`: one draw of every triangle (the soup): depth (test NEARER, writes on) and
   the G-buffer (world position, triangle).
2. per light (an area light: per sample, as a point light): `count_signed` — the stencil
   cleared, then the shadow volumes drawn with colour and depth writes off and two-sided
   stencil counting, z-pass or z-fail per caster; `mark_unshadowed` — a full-screen pass
   adding the light's bit where the count is 0.
3. `shade`: one full-screen pass (two draws split by the last light's stencil, which is not
   marked): ambient plus every unshadowed light's Phong term where n . l > 0 (and inside a
   spot's cone), the lit bits and coverage (up to LIGHTS_PER_PAGE lights a pass).
4. `encode_srgb`, when the 8-bit image is asked for.

A mask-only frame (the lit bits and coverage alone, one page of lights) has no G-buffer and no
shading pass: `mask_pass` is its geometry pass, writing shade.frag's lit bits (MASK_PASS) as if
no light were shadowed, and after each light's count `clear_shadowed` removes that light's bit
where the count is not 0 (a colour logic op on the unsigned-integer bits).

The forward passes (`forward`: depth and ambient, then per light over the soup with depth test
EQUAL) remain for the planar shadows.  Both compute the same numbers: the same depths (the same
invariant vertex shader on the same vertices in the same order) and the same lighting
expressions on the same float32 inputs (shade.frag repeats phong.frag's and scene.vert's).

Every pass takes the `pipeline.Pipeline` it draws with (and, where it needs the frame's
camera or lights, the `pipeline.FrameState`).  The volume count has three intents over one
draw sequence (`_counted`): `count_signed` (the shadow test), `count_entering` (the overflow
check's saturating bound) and `count_each_caster` (the ground truth's per-caster counters).

Depth is reversed (camera.NEARER is ">").  The depth test of the volume passes is "strictly
nearer", so that a volume face exactly at the surface's depth counts as behind it (z-fail near
caps tie with their own triangle; see `volumes`).
"""

from __future__ import annotations

import contextlib

import moderngl
import numpy as np

from shadowvol.raster import stencil
from shadowvol.raster.geometry import SceneGeometry
from shadowvol.raster.platform.gl import GL_AND_INVERTED, GL_OR
from shadowvol.raster.glsl import set_uniform
from shadowvol.raster.projection import (
    FAR_DEPTH,
    NEARER,
    gl_matrix,
    in_frame,
    planes_in_frame,
)
from shadowvol.scene import AreaSample, Camera, SpotLight

NO_CONE = -2.0  # u_spot_cos for lights without a cone (below any cosine)
# reversed depth: FAR_DEPTH (0) is the clear value and drawn surfaces lie above it, so a
# fragment at FAR_DEPTH passes "<" exactly where something was drawn
FARTHER_THAN_NOTHING = "<"


def set_camera(programs, view_proj: np.ndarray, camera: Camera, origin: np.ndarray) -> None:
    """The camera's uniforms in the frame of `origin` (3,): view_proj (4, 4) frame -> clip
    (`projection.frame_view_projection`), and the eye."""
    for p in programs:
        set_uniform(p, "u_view_proj", gl_matrix(view_proj))
        set_uniform(p, "u_eye", tuple(float(x) for x in camera.eye - origin))


def set_frame(pipe, frame) -> None:
    """The frame's camera set on the geometry and on the programs of `pipe` (its volumes'
    too): the GPU draws in the float32 frame of this camera's eye (`projection`), the ray
    tracer's frame for the same camera, so the geometry is re-expressed when the eye moves,
    and huge triangles are cut to the view (`guard`)."""
    vols = pipe.volumes
    if "casters" in frame.plan.outputs:
        vols.counting_programs()   # before set_camera: it sets their camera too
    vols.new_frame()
    pipe.geometry.move_to(frame.origin)
    pipe.geometry.set_view(frame.view_proj, frame.camera.near)
    set_camera((*pipe.programs.framed, *vols.programs), frame.view_proj, frame.camera,
               frame.origin)


def geometry_pass(pipe, cull: np.ndarray | None = None, marks: bool = True,
                  srgb_background: tuple[int, int, int] | None = None) -> None:
    """Clear the G-buffer, depth and stencil, then every triangle of the soup: one draw per run
    of objects with the same `cull` (n_objects,) bool, back faces culled where it is True (one
    draw for all when None or all alike).  `marks`: some light will be marked (more than one
    light in a page).  `srgb_background`: the shading pass will write 8-bit sRGB; its target
    is cleared to this code (`srgb_code` of the background)."""
    target = pipe.target
    target.clear_gbuffer(pipe.scene.background, marks)
    if srgb_background is not None:
        target.clear_srgb(srgb_background)
    target.use_gbuffer()
    _draw_soup(pipe.ctx, pipe.geometry, pipe.programs.gbuffer_vao, cull)
    target.use()


def _draw_soup(ctx: moderngl.Context, geometry: SceneGeometry, vao: moderngl.VertexArray,
               cull: np.ndarray | None) -> None:
    """Every triangle of the soup through `vao` (scene.vert), depth test NEARER with depth
    writes as the bound framebuffer has them: one draw per run of objects with the same `cull`
    (n_objects,) bool, back faces culled where it is True (one draw for all when None or all
    alike)."""
    ctx.enable_only(moderngl.DEPTH_TEST)
    ctx.depth_func = NEARER
    ctx.front_face = "ccw"
    ctx.cull_face = "back"
    ranges = geometry.ranges
    if cull is None or not cull.any():
        runs = [(0, len(ranges), False)]
    else:
        change = np.flatnonzero(np.diff(cull.astype(np.int8))) + 1
        starts = np.concatenate([[0], change])
        ends = np.concatenate([change, [len(ranges)]])
        runs = [(int(a), int(b), bool(cull[a])) for a, b in zip(starts, ends)]
    for a, b, culled in runs:
        ctx.enable_only(moderngl.DEPTH_TEST | (moderngl.CULL_FACE if culled else 0))
        # the soup but the huge triangles, then their pieces (`SceneGeometry.set_view`)
        for first, count in geometry.spans(range(a, b)):
            vao.render(moderngl.TRIANGLES, vertices=3 * count, first=3 * first)
    ctx.enable_only(moderngl.DEPTH_TEST)


def zero_unreceiving(pipe, count_mask: int = 0xFF) -> None:
    """After a light's count (`count_signed`, its framebuffer bound, colour and depth writes
    off): the objects that receive no shadow (`Object.receive_shadows`) drawn again over the
    geometry pass's depths (the same shader and vertices: depth test EQUAL holds), their
    visible pixels' counts set to 0 (`stencil.zeroed_counts`).  Nothing when all receive."""
    progs, ctx = pipe.programs, pipe.ctx
    if progs.receivers is None:
        return
    ctx.depth_func = "=="
    with stencil.zeroed_counts(pipe.gl, count_mask):
        for first, count in progs.geometry.spans(progs.unreceiving):
            progs.receivers_vao.render(moderngl.TRIANGLES, vertices=3 * count, first=3 * first)
    ctx.depth_func = NEARER


def mask_pass(pipe, frame, in_stencil: bool = False) -> None:
    """The geometry pass of a mask-only frame for its hard lights (one page) seen by its
    camera: depth and stencil cleared, then every triangle of
    the soup as `geometry_pass` draws it (the same vertex shader and vertices: the same
    depths), writing into `target.unshadowed` bit 0 (covered) and bit i + 1 where the visible
    side faces light i (n . l > 0, inside a spot's cone) by shade.frag's own tests
    (MASK_PASS: n . l per triangle in scene.vert, from the soup's normal and corner, the
    cone per pixel); pixels no triangle covers keep 0.  `in_stencil` (at most 6 lights): the
    same bits into the stencil instead, laid out as `stencil.mask_layout` says, and no colour
    written.  `target.mark_fbo` is left bound, for the counts and `clear_shadowed`."""
    lights, progs, gl = frame.hard_lights, pipe.programs, pipe.gl
    prog, vao = progs.mask_pass(
        len(lights), spots=sum(1 << i for i, l in enumerate(lights)
                               if isinstance(l, SpotLight)), in_stencil=in_stencil)
    fbo = pipe.target.mark_fbo
    fbo.depth_mask = True
    fbo.color_mask = (not in_stencil,) * 4
    stencil.clear_depth_stencil(gl, fbo.glo, FAR_DEPTH)
    if not in_stencil:
        stencil.clear_uint_attachment(gl, fbo.glo, 0, 0)
    fbo.use()
    origin = progs.geometry.origin
    set_camera((prog,), frame.view_proj, frame.camera, origin)
    set_uniform(prog, "u_first_page", True)
    _light_arrays(prog, lights, origin)
    with stencil.exported_bits(gl) if in_stencil else contextlib.nullcontext():
        _draw_soup(pipe.ctx, progs.geometry, vao, frame.cull)


def clear_shadowed(pipe, bit: int, zero: bool = False) -> None:
    """After light `bit`'s count in a mask-only frame (`mask_pass`): its lit bit (2^(bit + 1)
    of `target.unshadowed`) cleared at every covered pixel whose count is not 0 (the logic op
    AND-NOT).  `zero`: every count is left 0, as a clear would (`stencil.where_shadowed`),
    for the next light's count.  `target.mark_fbo` stays bound."""
    _bits_pass(pipe, 2 << bit, stencil.where_shadowed(pipe.gl, zero=zero), GL_AND_INVERTED)


def clear_shadowed_in_stencil(pipe, count_mask: int, light_bit: int) -> None:
    """`clear_shadowed` for a mask-only frame whose bits are in the stencil (`mask_pass`
    `in_stencil`): after a light's count (in the bits of `count_mask`), its `light_bit`
    cleared wherever the count is not 0, and every count left 0 for the next light
    (`stencil.where_shadowed` zeroing both); no colour written.  `target.mark_fbo` stays
    bound."""
    _bits_pass(pipe, 0, stencil.where_shadowed(
        pipe.gl, zero=True, count_mask=count_mask, also_zero=light_bit), None)


def mark_unshadowed(pipe, bit: int, restore: bool = True, zero: bool = False) -> None:
    """Set bit `bit` of the unshadowed bits where the stencil count is 0 (the logic op OR);
    `restore`: bind the target's main framebuffer after (else `target.mark_fbo` stays bound).
    `zero`: also set every other count to 0 (`stencil.where_unshadowed`), so that the next
    light's count needs no clear (`count_signed(clear=False)`)."""
    _bits_pass(pipe, 1 << bit, stencil.where_unshadowed(pipe.gl, zero=zero), GL_OR)
    if restore:
        pipe.target.use()


def _bits_pass(pipe, value: int, where, op: int | None) -> None:
    """One full-screen pass of mark.frag over the covered pixels into `target.unshadowed`
    (`mark_fbo`, left bound): `value` combined with the stored bits by the logic op `op`
    wherever the stencil test `where` (a context manager of `stencil`) passes; `op` None: no
    colour written, the stencil operations of `where` alone."""
    ctx, progs = pipe.ctx, pipe.programs
    fbo = pipe.target.mark_fbo
    fbo.depth_mask = False
    fbo.color_mask = (op is not None,) * 4
    fbo.use()
    ctx.enable_only(moderngl.NOTHING)
    set_uniform(progs.mark, "u_bit", value)
    _only_where_covered(ctx)
    with where, (contextlib.nullcontext() if op is None else stencil.logic_op(pipe.gl, op)):
        progs.mark_vao.render(moderngl.TRIANGLES, vertices=3)
    ctx.enable_only(moderngl.DEPTH_TEST)
    ctx.depth_func = NEARER


def _only_where_covered(ctx: moderngl.Context) -> None:
    """The depth test of the full-screen passes (blending as it was): their triangle lies at
    FAR_DEPTH, the depth of nothing drawn, and passes where the stored depth is farther from
    FAR_DEPTH than it (any drawn surface; depth writes are off), so uncovered pixels cost no
    shading."""
    ctx.enable(moderngl.DEPTH_TEST)
    ctx.depth_func = FARTHER_THAN_NOTHING


def shade(pipe, camera: Camera, lights, first_page: bool, colour: bool = True,
          srgb: bool = False) -> None:
    """The one shading pass for `lights` (at most LIGHTS_PER_PAGE) seen by `camera`: colour
    and bits of every
    pixel.  The unshadowed target holds bits 0.. of all but the last light; the stencil holds
    the last light's count, and the pass is drawn where it is 0 and where it is not (each
    pixel once), which spares the last light its marking pass and, for one light, the
    unshadowed fetch.  A page after the first is added to the first (additive blending; no
    ambient, no coverage) and its bits must be cleared before.  `colour=False`: the lit bits
    only.  `srgb`: the colour encoded to 8-bit sRGB into `target.srgb` instead (one page only:
    pages add up in float), exactly as `encode_srgb` would encode it."""
    ctx, gl, target, progs = pipe.ctx, pipe.gl, pipe.target, pipe.programs
    prog, vao = progs.shading(
        len(lights), colour, srgb,
        spots=sum(1 << i for i, l in enumerate(lights) if isinstance(l, SpotLight)),
        emitters=sum(1 << i for i, l in enumerate(lights) if isinstance(l, AreaSample)))
    fbo = target.srgb_shade_fbo if srgb else target.fbo
    fbo.depth_mask = False
    fbo.color_mask = [(colour,) * 4, (True,) * 4]
    fbo.use()
    if first_page:
        ctx.enable_only(moderngl.NOTHING)
    else:
        ctx.enable_only(moderngl.BLEND)
        ctx.blend_func = moderngl.ONE, moderngl.ONE
        ctx.blend_equation = moderngl.FUNC_ADD
    _only_where_covered(ctx)
    origin = progs.geometry.origin   # positions in the geometry's frame, as the G-buffer's
    set_uniform(prog, "u_eye", tuple(float(x) for x in camera.eye - origin))
    set_uniform(prog, "u_first_page", first_page)
    _light_arrays(prog, lights, origin)
    set_uniform(prog, "u_ambient", tuple(float(x) for x in pipe.scene.ambient))
    progs.geometry.materials.use(0)
    target.position.use(1)
    target.unshadowed.use(2)
    for name, unit in (("u_materials", 0), ("u_position", 1), ("u_unshadowed", 2)):
        set_uniform(prog, name, unit)
    progs.geometry.triangle_data.bind_to_storage_buffer(0)
    if colour and progs.geometry.surface:
        progs.geometry.textures.bind(prog, target)
    if not lights:
        set_uniform(prog, "u_last_unshadowed", False)
        vao.render(moderngl.TRIANGLES, vertices=3)
    else:
        for unshadowed, test in ((True, stencil.where_unshadowed),
                                 (False, stencil.where_shadowed)):
            set_uniform(prog, "u_last_unshadowed", unshadowed)
            with test(gl):
                vao.render(moderngl.TRIANGLES, vertices=3)
    ctx.enable_only(moderngl.DEPTH_TEST)
    ctx.depth_func = NEARER
    target.use()


def _light_arrays(prog: moderngl.Program, lights, origin: np.ndarray) -> None:
    """shade.frag's per-light uniform arrays for `lights`, in the frame of `origin` (3,)."""
    # uniform arrays as packed float32 (glUniform*fv): the same float32 values the forward
    # pass's single uniforms hold
    spot = [isinstance(l, SpotLight) for l in lights]
    arrays = {
        "u_light": [in_frame(l.homogeneous, origin) for l in lights],
        "u_radiance": [l.radiance for l in lights],
        "u_spot_direction": [l.direction if s else (0.0, 0.0, 1.0) for l, s in zip(lights, spot)],
        "u_spot_cos": [l.cos_cutoff if s else NO_CONE for l, s in zip(lights, spot)],
        "u_emitter_cosine": [1.0 if isinstance(l, AreaSample) else 0.0 for l in lights]}
    for name, values in arrays.items() if lights else ():
        if name not in prog:
            continue
        # the linker keeps an array up to the last element the shader reads (the spots' up to
        # the last spot's)
        kept = values[:prog[name].array_length]
        set_uniform(prog, name, np.array([np.asarray(v, np.float64) for v in kept],
                                         np.float32).tobytes())


def srgb_code(pipe, rgb) -> tuple[int, int, int]:
    """The 8-bit sRGB code of the linear colour `rgb` (3,) as srgb.frag encodes it (on the GPU,
    so that a pixel cleared to it is the pixel the sRGB pass would have written)."""
    ctx, progs = pipe.ctx, pipe.programs
    src = ctx.texture((1, 1), 4, np.array([*rgb, 0.0], np.float32).tobytes(), dtype="f4")
    out = ctx.texture((1, 1), 4, dtype="f1")
    fbo = ctx.framebuffer(color_attachments=[out])
    try:
        fbo.use()
        ctx.enable_only(moderngl.NOTHING)
        src.use(0)
        set_uniform(progs.srgb, "u_colour", 0)
        progs.srgb_vao.render(moderngl.TRIANGLES, vertices=3)
        code = np.frombuffer(fbo.read(components=3, dtype="f1"), np.uint8)
    finally:
        for obj in (fbo, out, src):
            obj.release()
        ctx.enable_only(moderngl.DEPTH_TEST)
    return tuple(int(c) for c in code)


def encode_srgb(pipe) -> None:
    """The colour attachment encoded to 8-bit sRGB into `target.srgb`, rows flipped."""
    ctx, target, progs = pipe.ctx, pipe.target, pipe.programs
    target.srgb_fbo.use()
    ctx.enable_only(moderngl.NOTHING)
    target.colour.use(0)
    set_uniform(progs.srgb, "u_colour", 0)
    progs.srgb_vao.render(moderngl.TRIANGLES, vertices=3)
    ctx.enable_only(moderngl.DEPTH_TEST)
    target.use()


def count_signed(pipe, zfail: np.ndarray, *, halve: bool = False,
                 clip_planes: np.ndarray | None = None, objects=None, fbo=None,
                 clear: bool = True, count_mask: int = 0xFF, receivers: bool = False) -> None:
    """Stencil := the signed count of shadow volumes around each visible point, for the light
    `pipe.volumes` was prepared for (`stencil.zpass_counting`, `stencil.zfail_counting`).
    zfail : (n_objects,) bool, the method per caster.

    `halve`: z-pass casters whose multiplicities are all even count half (see
    `CpuVolumes.draw_sides`): the stencil is then 0 exactly where it would have been 0, but
    the counts themselves differ.  Only for casters that z-pass counts correctly.

    `clip_planes` : (6, 4) float64 or None, the box of `methods.zpass_clip_planes`: z-pass
    side quads are clipped to it (counts at covered pixels unchanged, uncovered ones not).

    `objects` : the casters to count (default all; only casting objects count).

    `fbo` : count in this framebuffer of the target (one sharing its depth-stencil buffer,
    e.g. `target.mark_fbo`) with colour writes off, and leave it bound, instead of the
    target's main one: a frame that marks after each count then changes no framebuffer
    between lights, and llvmpipe, which flushes its scene at every change, bins the volume and
    mark passes of all its lights together.

    `clear=False`: the stencil is known to be 0 already (the geometry pass's clear, or a
    zeroing mark), and is not cleared again.

    `count_mask`: the count is kept in these low bits of the stencil only
    (`stencil.mask_layout`: the mask-only frame's bits are above them).  `receivers`: then
    `zero_unreceiving` (the shadow switches)."""
    gl = pipe.gl

    def counting(zfail_group: bool, depth_clamp: bool):
        return (stencil.zfail_counting(gl, depth_clamp=depth_clamp, count_mask=count_mask)
                if zfail_group else stencil.zpass_counting(gl, count_mask=count_mask))
    _bind_for_count(pipe, fbo, clear)
    _counted(pipe, zfail, objects, counting, halve, clip_planes)
    if receivers:
        zero_unreceiving(pipe, count_mask)
    if fbo is None:
        pipe.target.use()


def count_entering(pipe, zfail: np.ndarray, *, halve: bool = False,
                   clip_planes: np.ndarray | None = None) -> None:
    """The stencil-overflow check's count (`overflow.detect.find_wrapped`): the same faces in
    the same groups as `count_signed`, under `stencil.entering_faces_counting` (only the
    faces by which a view ray enters a volume, saturating at 255), the stencil cleared
    first."""
    gl = pipe.gl

    def counting(zfail_group: bool, depth_clamp: bool):
        return stencil.entering_faces_counting(gl, zfail=zfail_group, depth_clamp=depth_clamp)
    _bind_for_count(pipe, None, True)
    _counted(pipe, zfail, None, counting, halve, clip_planes)
    pipe.target.use()


def count_each_caster(pipe, zfail: np.ndarray, objects, *, each, counting,
                      halve: bool = False, clip_planes: np.ndarray | None = None) -> None:
    """The ground truth's per-caster counts (`truth.truth_pass.CasterCounts`): the same faces
    in the same groups as `count_signed`, drawn with the volumes' counting programs
    (caster_count.frag), each object of `objects` alone after `each(program, i)` is called
    with its program and index, under the stencil state `counting(zfail, depth_clamp)` (a
    context manager).  The stencil is not cleared first."""
    _bind_for_count(pipe, None, False)
    _counted(pipe, zfail, objects, counting, halve, clip_planes, each)
    pipe.target.use()


def _bind_for_count(pipe, fbo, clear: bool) -> None:
    """The count's framebuffer bound, colour and depth writes off; its stencil cleared if
    `clear`."""
    if fbo is not None:
        fbo.depth_mask = False
        fbo.color_mask = (False,) * 4
        fbo.use()
        if clear:
            stencil.clear_stencil(pipe.gl, fbo.glo)
    else:
        if clear:
            pipe.target.clear_stencil()
        pipe.target.use(colour=False, depth=False)


def _counted(pipe, zfail: np.ndarray, objects, counting, halve: bool,
             clip_planes: np.ndarray | None, each=None) -> None:
    """The one draw sequence of every volume count: the casting objects of `objects` (all
    when None), z-pass casters' sides (clipped to `clip_planes` when given), then z-fail
    casters' sides, far caps (depth clamped) and near caps, each group under its
    `counting(zfail, depth_clamp)` stencil state."""
    ctx, gl, volumes = pipe.ctx, pipe.gl, pipe.volumes
    ctx.enable_only(moderngl.DEPTH_TEST)  # no culling: both faces count
    ctx.depth_func = NEARER
    chosen = np.ones(len(zfail), bool) if objects is None else np.isin(
        np.arange(len(zfail)), list(objects))
    chosen &= volumes.geometry.casts
    # index arrays, not lists: the volumes draw them in numpy (no Python per object)
    by_zpass = np.flatnonzero(~zfail & chosen)
    by_zfail = np.flatnonzero(zfail & chosen)
    if len(by_zpass) and clip_planes is not None:
        frame_planes = planes_in_frame(clip_planes, volumes.geometry.origin)
        for p in volumes.programs:
            set_uniform(p, "u_clip_planes", frame_planes.astype(np.float32).tobytes())
        with counting(False, False), stencil.clip_distances(gl, len(clip_planes)):
            volumes.draw_sides(by_zpass, halve=halve, clipped=True, each=each)
    elif len(by_zpass):
        with counting(False, False):
            volumes.draw_sides(by_zpass, halve=halve, each=each)
    if len(by_zfail):
        with counting(True, False):   # sides clipped, not clamped: see zfail_counting
            volumes.draw_sides(by_zfail, each=each)
        with counting(True, True):
            volumes.draw_caps(by_zfail, near=False, each=each)
        with counting(True, False):
            volumes.draw_caps(by_zfail, near=True, each=each)
