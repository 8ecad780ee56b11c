"""The shadow-volume renderer: `Renderer` for many frames of one scene, `render` for one.

A Renderer holds one GL context (its own, or one it is given), uploads the scene's geometry once,
and renders deferred frames: one geometry pass (depth, ambient, G-buffer), then per light the
stencil count of its shadow volumes and a full-screen pass adding its Phong term where the
count is 0 (see `passes`).  It returns arrays only, and only those asked for (`outputs=`);
files are the CLI's business.

Limit: the stencil is 8 bits and counts wrap (INCR_WRAP / DECR_WRAP).  Every triangle casts, so
a pixel behind k closed meshes counts 2k; 256 layers over one pixel would read 0, i.e. lit.  That
needs about 128 closed objects (or 256 open sheets) lined up between one point and one light.
It is detected (`overflow`): when conservative bounds (the scene's, then the light's:
`detect.light_bound`) say a count could reach 256, one more saturating volume pass for that
light finds the pixels that may have wrapped, and render() raises
detect.StencilOverflowError instead of returning a wrong shadow.
"""

from __future__ import annotations

from dataclasses import replace

import moderngl
import numpy as np

from shadowvol.cameras import calibration
from shadowvol.frame import LAYERS, check_light_kinds, check_outputs
from shadowvol.raster import bits, layers, methods, overlay, passes
from shadowvol.raster.overflow import detect
from shadowvol.raster.truth import truth_pass
from shadowvol.raster import stencil as stencil_gl
from shadowvol.raster.platform.context import (
    clear_errors,
    create_context,
    errors_cleared_on_failure,
    make_current,
)
from shadowvol.raster.geometry import SceneGeometry
from shadowvol.raster.platform.gl import RawGL
from shadowvol.raster.object_facts import ObjectFacts
from shadowvol.raster.overflow.policy import LightBounds
from shadowvol.raster.plan import FramePlan
from shadowvol.raster.projection import frame_view_projection
from shadowvol.raster.recycle import ArrayPool
from shadowvol.raster.result import (DEFAULT_OUTPUTS, OUTPUTS, SILHOUETTES, RenderResult,
                                     check_lights)
from shadowvol.raster.target import LIGHTS_PER_PAGE, Target, check_frame_size
from shadowvol.raster.truth.assemble import frame_truth
from shadowvol.raster.volumes.builder import VolumeBuilder
from shadowvol.raster.volumes.cpu import CpuVolumes
from shadowvol.raster.volumes.gpu import GpuVolumes
from shadowvol.scene import Camera, Light, Scene, hard_lights

class Renderer:
    """Renders `scene` (its geometry and materials; camera and lights may change per frame).

    Use as a context manager or call `release()`: every GL object it made is released, and the
    context too if the renderer created it.
    """

    # stencil-overflow bounds (`detect.light_bound`, 0.1-0.6 s each) computed in one frame
    BOUNDS_PER_FRAME = 1

    def __init__(self, scene: Scene, ctx: moderngl.Context | None = None):
        self.scene = scene
        self._own_ctx = ctx is None
        self.ctx = create_context() if ctx is None else ctx
        self._owned = []
        self._volumes: dict[str, VolumeBuilder] = {}
        self._truth: truth_pass.TruthPass | None = None
        self._bounds = LightBounds()   # the overflow check's kept light bounds
        self._srgb_code: tuple[int, int, int] | None = None   # `_srgb_background`
        # the arrays frames return (`recycle`), and the frames' own scratch (`_scratch`)
        self._pool = ArrayPool()
        self._scratches: list[np.ndarray] = []
        # back-face culling in the geometry pass for closed convex casters beyond the near
        # plane (`methods.cullable`): 14-22% of a frame here, but OFF by default because it is
        # not exact at float32 depth ties: where a silhouette's back face won the depth test by
        # rounding, the front face shows instead (one pixel of scenes/whitted.toml)
        self.cull_back_faces = False
        # the stencil-overflow check (see `overflow`): on by default; it costs one more volume
        # pass per light, and only in scenes whose bound allows a count of 256
        self.check_overflow = True
        # a mask-only frame of up to 6 hard lights keeps its bits in the stencil where the
        # counts leave room (`_masks_fit_stencil`); off: always in a colour target (the same
        # masks bit for bit: tests compare the two)
        self.masks_in_stencil = True
        self._stencil_export: bool | None = None   # ARB_shader_stencil_export, looked up once
        try:
            # every public method first makes the context current: raw GL calls
            # (gl.RawGL) go to whichever context is current, e.g. after another renderer
            # with its own context has run
            make_current(self.ctx)
            check_frame_size(self.ctx, scene.width, scene.height)  # bad input, not a GL error
            self.gl = RawGL()
            self.geometry = self._own(SceneGeometry(self.ctx, scene))
            self._facts = ObjectFacts(self.geometry)
            self.target = self._own(Target(self.ctx, self.gl, scene.width, scene.height,
                                           surface=self.geometry.surface))
            self.programs = self._own(passes.ScenePrograms(self.ctx, self.geometry))
        except BaseException:
            ctx = self.ctx
            self.release()
            if not self._own_ctx:  # the caller's context keeps no GL error of this failure
                clear_errors(ctx)
            raise

    def _own(self, obj):
        self._owned.append(obj)
        return obj

    def volumes(self, silhouettes: str) -> VolumeBuilder:
        """The volume builder for "cpu" or "gpu" silhouettes (made on first use)."""
        if silhouettes not in SILHOUETTES:
            raise ValueError(f"silhouettes must be 'cpu' or 'gpu', got {silhouettes!r}")
        if silhouettes not in self._volumes:
            cls = CpuVolumes if silhouettes == "cpu" else GpuVolumes
            make_current(self.ctx)
            self._volumes[silhouettes] = self._own(cls(self.ctx, self.geometry))
        return self._volumes[silhouettes]

    def render(self, method: str = "auto", silhouettes: str = "cpu", *,
               camera: Camera | None = None, lights: tuple[Light, ...] | None = None,
               stencil: bool = False, shadows: bool = True,
               outputs: tuple[str, ...] | None = None) -> RenderResult:
        """One frame.  `method`: "auto" (z-fail only for casters the near plane may cut),
        "zpass" or "zfail".  `camera`/`lights` override the scene's for this frame.
        `outputs`: exactly the arrays to read back (names in `result.OUTPUTS`; default image,
        lit and coverage), for lean frames; the others are None in the result (the function
        `render` adds `outputs` to the defaults instead).  `stencil=True` adds "stencil": the
        per-light stencil counts (one extra read-back each).  `shadows=False` skips the volume
        passes (every count stays 0): the same frame without shadows, the benchmark's
        baseline."""
        if method not in methods.METHODS:
            raise ValueError(f"method must be one of {', '.join(methods.METHODS)}, "
                             f"got {method!r}")
        outputs = set(check_outputs(outputs, OUTPUTS, DEFAULT_OUTPUTS)) | (
            {"stencil"} if stencil else set())
        wanted_layers, outputs = outputs & set(LAYERS), outputs - set(LAYERS)
        lights = check_lights(lights)
        make_current(self.ctx)
        to_check = self._lights_to_check(camera, lights) if shadows else []
        # the overflow check needs the lit masks, asked for or not
        plan = FramePlan.of(method, outputs | ({"lit"} if to_check else set()))
        with errors_cleared_on_failure(self.ctx), stencil_gl.zero_to_one_depth(self.gl):
            result = self._render(plan, silhouettes, camera, lights, shadows)
            if to_check:
                detect.check_frame(self, result, silhouettes, camera, lights,
                                     halve=plan.halve, only=to_check)
            if "lit" not in outputs:
                result = replace(result, lit=None, lit_count=None)
        if wanted_layers:   # the intrinsic layers: more frames (`layers`)
            result = replace(result, **layers.render_layers(
                self, method, silhouettes, camera, lights, shadows, wanted_layers))
        return result

    def _lights_to_check(self, camera, lights) -> list[tuple[int, int]]:
        """(light, sample) indices of the hard lights whose stencil count might reach 256 in
        this frame: none when the scene's bound is below it, else those whose
        `detect.light_bound` is not (`overflow_policy`: at most `BOUNDS_PER_FRAME` bounds
        computed in one frame, so a frame costs at most one bound more than its re-checks)."""
        if not self.check_overflow or self.count_bound < detect.STENCIL_LIMIT:
            return []
        camera = self.scene.camera if camera is None else camera
        lights = self.scene.lights if lights is None else lights
        return self._bounds.to_check(self.geometry, self.scene.height, lambda: self.convex,
                                     camera, lights, self.BOUNDS_PER_FRAME)

    @property
    def _light_bounds(self) -> dict[bytes, tuple | None]:
        """`overflow_policy.LightBounds.kept`: the light bounds kept."""
        return self._bounds.kept

    # the objects' facts (`object_facts.ObjectFacts`), each computed once, when first asked
    convex = property(lambda self: self._facts.convex,
                      doc="(n_objects,) bool: closed convex meshes")
    outward_convex = property(lambda self: self._facts.outward_convex,
                              doc="(n_objects,) bool: closed convex meshes wound outward")
    object_bounds = property(lambda self: self._facts.object_bounds,
                             doc="(n_objects,) int64: a bound on each object's own count")
    count_bound = property(lambda self: self._facts.count_bound,
                           doc="the casting objects' count bound: below 256 none can wrap")

    def _srgb_background(self) -> tuple[int, int, int]:
        """The background's 8-bit sRGB code as the sRGB pass encodes it (once per renderer)."""
        if self._srgb_code is None:
            self._srgb_code = passes.srgb_code(self.ctx, self.programs, self.scene.background)
        return self._srgb_code

    def _scratch(self, k: int) -> np.ndarray:
        """(H, W) uint32 scratch k of this renderer (0: masked bits, 1..: a page's bits), for
        work within one frame; never returned."""
        while len(self._scratches) <= k:
            self._scratches.append(np.empty((self.scene.height, self.scene.width), np.uint32))
        return self._scratches[k]

    def _scratch_bytes(self, k: int) -> np.ndarray:
        """(H, W) uint8 in the first quarter of `_scratch(k)`'s memory."""
        h, w = self.scene.height, self.scene.width
        return self._scratch(k).reshape(-1).view(np.uint8)[:h * w].reshape(h, w)

    def _truth_pass(self) -> truth_pass.TruthPass:
        if self._truth is None:
            self._truth = self._own(truth_pass.TruthPass(self.ctx, self.target))
        return self._truth

    def _render(self, plan: FramePlan, silhouettes, camera, lights, shadows) -> RenderResult:
        camera = self.scene.camera if camera is None else camera
        lights = self.scene.lights if lights is None else tuple(lights)
        outputs = plan.outputs
        vols = self.volumes(silhouettes)
        if "casters" in outputs:
            vols.counting_programs()   # before set_camera: it sets their camera too
        vols.new_frame()
        view_proj, clip, cull = self._set_frame(camera, vols, plan.want_stencil)
        # an area light is its samples, each counted and shaded as a point light
        hard = [(i, sample) for i, lt in enumerate(lights) for sample in hard_lights(lt)]
        # the 8-bit image straight from the shading pass when the float one is not asked for
        # and one page holds every light (pages add up in float)
        srgb_direct = ("image_srgb" in outputs and "image" not in outputs
                       and len(hard) <= LIGHTS_PER_PAGE)
        h, w = self.scene.height, self.scene.width
        check_light_kinds(plan.outputs, lights)
        zfail = np.zeros((len(lights), len(self.scene.objects)), bool)
        truth_pages: list = []
        counts: list[np.ndarray] = []
        in_stencil = None   # the mask-only frame's stencil bytes, when it keeps its bits there
        pages: list[np.ndarray] = []
        if outputs <= {"lit", "coverage"} and len(hard) <= LIGHTS_PER_PAGE:
            # the masks alone, one page: no G-buffer and no shading pass
            if self._masks_fit_stencil(hard, lights, shadows):
                in_stencil = self._mask_frame(plan, camera, view_proj, hard, shadows, vols,
                                              clip, cull, zfail, in_stencil=True)
            else:
                pages = [self._mask_frame(plan, camera, view_proj, hard, shadows, vols, clip,
                                          cull, zfail)]
        else:
            pages = self._deferred_frame(plan, camera, hard, shadows, vols, clip, cull,
                                         zfail, srgb_direct, truth_pages, counts)
        # what the caller gets comes from the pool (`recycle`); numpy's temporaries go to
        # the scratch (3 MB of new memory costs a millisecond here)
        pool = self._pool
        image = (self.target.read_image(out=pool.empty((h, w, 3), np.float32))
                 if "image" in outputs else None)
        samples = np.array([len(hard_lights(lt)) for lt in lights], np.int64)
        coverage, lit, lit_count = self._read_masks(outputs, hard, samples, in_stencil, pages)
        extra = frame_truth(self, plan, camera, lights, hard, truth_pages, vols, clip)
        if plan.facing_pass:
            # the facing pass's lit: facing & unshadowed, bit for bit, summed over samples
            lit, counted = extra.pop("lit"), extra.pop("lit_count")
            if lit_count is not None:
                lit_count = counted
            for name in ("facing", "facing_count"):
                if name not in plan.asked:  # computed for casters only
                    extra.pop(name)
        srgb = None
        if "image_srgb" in outputs:
            if not srgb_direct:   # encoded from the float image, by its own pass
                passes.encode_srgb(self.ctx, self.target, self.programs)
            srgb = self.target.read_srgb(flipped=not srgb_direct,
                                         out=pool.empty((h, w, 3), np.uint8))
        return RenderResult(
            image=image, lit=lit, coverage=coverage,
            stencil=np.array(counts, np.int16).reshape(len(lights), h, w)
            if plan.want_stencil else None,
            zfail=zfail, lit_count=lit_count, samples=samples, image_srgb=srgb,
            calibration=calibration(self.scene.replace(camera=camera, lights=lights)),
            **extra)

    def _set_frame(self, camera, vols, want_stencil: bool) -> tuple:
        """The frame's camera set on the geometry and the programs: (view_proj, the z-pass
        clip planes or None, the back faces to cull or None)."""
        # the GPU draws in the float32 frame of this camera's eye (`projection`), the ray
        # tracer's frame for the same camera: the geometry is re-expressed when the eye moves
        view_proj, origin = frame_view_projection(camera, self.scene.size)
        self.geometry.move_to(origin)
        self.geometry.set_view(view_proj, camera.near)   # huge triangles cut (`guard`)
        passes.set_camera((*self.programs.framed, *vols.programs), view_proj, camera, origin)
        cull = methods.cullable(self.geometry.bounds, self.outward_convex, camera,
                                self.geometry.extent) if self.cull_back_faces else None
        # z-pass faces clipped to the box of the near rectangle and the casters: the same
        # counts at covered pixels, not at uncovered ones (see methods.zpass_clip_planes)
        clip = None if want_stencil else methods.zpass_clip_planes(
            self.geometry.bounds, camera, self.scene.size, self.geometry.extent)
        return view_proj, clip, cull

    def _read_masks(self, outputs, hard, samples, in_stencil, pages) -> tuple:
        """(coverage, lit, lit_count), each None unless asked for, in the pool's memory
        (`bits` decodes them)."""
        h, w, pool = self.scene.height, self.scene.width, self._pool
        masked = self._scratch(0)
        coverage = lit = lit_count = None
        if "coverage" in outputs:
            coverage = pool.empty((h, w), bool)
            bits.coverage(in_stencil, pages, masked, coverage)
        if "lit" in outputs:
            lit_count = pool.empty((len(samples), h, w), np.uint16)
            lit = pool.empty((len(samples), h, w), bool)
            if in_stencil is not None:
                bits.lit_from_stencil(in_stencil, hard, lit, lit_count, self._scratch_bytes(0))
            else:
                bits.lit_from_pages(pages, hard, samples, lit, lit_count, masked)
        return coverage, lit, lit_count

    def _masks_fit_stencil(self, hard, lights, shadows: bool) -> bool:
        """Whether a mask-only frame of `hard` (its hard lights, one page) keeps its bits in
        the stencil beside the counts (`stencil.mask_layout`): at most 6 lights, none an area
        light (whose samples' counts add up in lit_count), no count of the scene able to
        reach 2^(7 - lights) in magnitude (`count_bound`), and a GL that lets a fragment
        shader write the stencil (ARB_shader_stencil_export; without it, and when
        `masks_in_stencil` is off, the bits go to a colour target)."""
        if (not self.masks_in_stencil or len(hard) != len(lights)
                or not 1 <= len(hard) <= stencil_gl.MASK_LAYOUT_LIGHTS):
            return False
        if self._stencil_export is None:
            self._stencil_export = "GL_ARB_shader_stencil_export" in self.ctx.extensions
        return self._stencil_export and (not shadows or
                                         self.count_bound < 1 << (7 - len(hard)))

    def _mask_frame(self, plan: FramePlan, camera, view_proj, hard, shadows, vols, clip, cull,
                    zfail, in_stencil: bool = False) -> np.ndarray:
        """The lit bits of a mask-only frame of the hard lights `hard` ((light index, hard
        light) pairs, one page): (H, W) uint32 in this renderer's scratch, bit 0 covered, bit
        k + 1 lit by hard[k], as the deferred frame's.  No G-buffer and no shading pass
        (`passes.mask_pass`); every light counted and its bit cleared where its count is not
        0 in one framebuffer, so that llvmpipe bins all of them in one scene.  Fills
        `zfail`.

        `in_stencil` (`_masks_fit_stencil`): the bits are kept in the stencil's high bits and
        each count in its low bits (`stencil.mask_layout`); the lights but the last are
        cleared where counted, the last light's count is left in place, and the stencil is
        returned as stored, (H, W) uint8 in this renderer's scratch: no colour target, no
        pass after the last count, one byte a pixel read."""
        progs, target = self.programs, self.target
        passes.mask_pass(self.ctx, self.gl, target, progs, view_proj, camera,
                         [sample for _, sample in hard], cull, in_stencil=in_stencil)
        count_mask, light_bits = (stencil_gl.mask_layout(len(hard)) if in_stencil
                                  else (0xFF, ()))
        for k, (i, light) in enumerate(hard):
            light4 = light.homogeneous
            choice = methods.choose(plan.method, self.geometry.bounds, camera,
                                    self.scene.size, light4, self.geometry.extent)
            if shadows and light.shadows:   # a light switched off: its bit stays facing
                vols.prepare(light4)
                # the counts are 0: the mask pass cleared them, and each light's clear but the
                # last zeroes them again (`stencil.where_shadowed`)
                passes.count_volumes(self.ctx, self.gl, target, vols, choice,
                                     halve=plan.halve, clip_planes=clip, receivers=progs,
                                     fbo=target.mark_fbo, clear=False, count_mask=count_mask)
                if not in_stencil:
                    passes.clear_shadowed(self.ctx, self.gl, target, progs, k,
                                          zero=k < len(hard) - 1)
                elif k < len(hard) - 1:
                    passes.clear_shadowed_in_stencil(self.ctx, self.gl, target, progs,
                                                     count_mask, light_bits[k])
            zfail[i] |= choice
        if in_stencil:
            bits = target.read_stencil_bits(out=self._scratch_bytes(1))
        else:
            bits = target.read_unshadowed(out=self._scratch(1))
        target.use()
        return bits

    def _deferred_frame(self, plan: FramePlan, camera, hard, shadows, vols, clip, cull, zfail,
                        srgb_direct, truth_pages, counts) -> list[np.ndarray]:
        """The deferred frame (`passes`): the lit bits of each page of LIGHTS_PER_PAGE hard
        lights (as `_mask_frame`'s; none when neither masks nor coverage are asked for and
        the colour is).  Fills `zfail`, `truth_pages` (the facing pass's, for the ground
        truth) and `counts` (each hard light's stencil counts, when asked for)."""
        progs, target = self.programs, self.target
        outputs, want_stencil, facing_pass = plan.outputs, plan.want_stencil, plan.facing_pass
        colour = bool({"image", "image_srgb"} & outputs)
        need_bits = "lit" in outputs or "coverage" in outputs or not colour
        # the unshadowed bits are cleared when some light of the first page is marked
        # (and always for the facing pass, which marks every light)
        passes.geometry_pass(self.ctx, target, progs, self.scene, cull,
                             marks=len(hard) > 1 or facing_pass,
                             srgb_background=self._srgb_background() if srgb_direct else None)
        pages = []
        # hard lights go in pages of LIGHTS_PER_PAGE: each one's volume count marks its
        # unshadowed bit, then one shading pass per page (one for any usual frame)
        # the stencil is all 0: the geometry pass cleared it, and each mark but a page's last
        # zeroes it again (no clear, each one a flush of llvmpipe's scene, before a count); a
        # page's last count stays for `shade`, so the next page clears it
        stencil_zero = True
        for first in range(0, max(len(hard), 1), LIGHTS_PER_PAGE):
            page_lights = [sample for _, sample in hard[first:first + LIGHTS_PER_PAGE]]
            if first:
                target.clear_unshadowed()
                target.clear_lit()
            for bit, light in enumerate(page_lights):
                light4 = light.homogeneous
                choice = methods.choose(plan.method, self.geometry.bounds, camera,
                                        self.scene.size, light4, self.geometry.extent)
                if shadows and light.shadows:
                    vols.prepare(light4)
                    # halving is safe only for casters `auto` chose z-pass for, and only when
                    # the counts themselves are not returned (see passes.count_volumes)
                    passes.count_volumes(self.ctx, self.gl, target, vols, choice,
                                         halve=plan.halve, receivers=progs,
                                         clip_planes=clip,
                                         # counted where it is marked: no framebuffer
                                         # change between the page's lights (llvmpipe
                                         # flushes at each)
                                         fbo=None if want_stencil else target.mark_fbo,
                                         clear=not stencil_zero)
                    stencil_zero = False
                elif not stencil_zero:
                    target.clear_stencil()
                    stencil_zero = True
                if want_stencil:
                    counts.append(target.read_stencil())
                if bit < len(page_lights) - 1:   # the last light's stencil is read by `shade`
                    passes.mark_unshadowed(self.ctx, self.gl, target, progs, bit,
                                           restore=False, zero=True)
                    stencil_zero = True
                zfail[hard[first + bit][0]] |= choice
            passes.shade(self.ctx, self.gl, target, progs, self.scene, camera, page_lights,
                         first_page=not first, colour=colour, srgb=srgb_direct)
            if need_bits:   # the frame's own scratch: read, used and dropped in this frame
                pages.append(target.read_bits(out=self._scratch(len(pages) + 1)))
            if facing_pass and page_lights:
                # the facing pass reads every light's unshadowed bit: mark the last one's too
                # (the stencil still holds its count)
                passes.mark_unshadowed(self.ctx, self.gl, target, progs, len(page_lights) - 1)
                truth_pages.append(self._truth_pass().run(target, self.geometry, page_lights))
        return pages

    def facing(self, *, camera: Camera | None = None,
               lights: tuple[Light, ...] | None = None) -> np.ndarray:
        """(L, H, W) bool: some sample of each light faces the pixel (n . l > 0 toward it and
        inside its cone), shadows aside: the frame without the volume passes.  With a
        frame's `lit_count`, umbra = facing & (lit_count == 0)."""
        return self.render(camera=camera, lights=lights, shadows=False,
                           outputs=("lit",)).lit_count > 0

    def volume_view(self, method: str = "auto", silhouettes: str = "cpu", *,
                    camera: Camera | None = None,
                    lights: tuple[Light, ...] | None = None) -> np.ndarray:
        """(H, W, 3) float32 linear RGB: the frame lit by `lights` (default: the scene's, as in
        `render`) with their shadow-volume polygons drawn over it, coloured by role (see
        `overlay`).  The polygons are exactly those the stencil pass drew under `method`."""
        lights = check_lights(lights)
        result = self.render(method, silhouettes, camera=camera, lights=lights)
        vols = self.volumes(silhouettes)  # the frame is left in the target
        with stencil_gl.zero_to_one_depth(self.gl):
            for i, light in ((i, hard) for i, lt in enumerate(self.scene.lights if lights is None
                                                              else lights)
                             for hard in hard_lights(lt) if hard.shadows):  # every sample
                vols.prepare(light.homogeneous)
                overlay.draw_volume_overlay(self.ctx, self.gl, self.target, vols,
                                            result.zfail[i])
        return np.ascontiguousarray(self.target.read_colour()[..., :3])

    def release(self) -> None:
        if self.ctx is None:
            return
        make_current(self.ctx)
        while self._owned:
            self._owned.pop().release()
        self._pool.clear()
        self._scratches.clear()
        if self._own_ctx:
            self.ctx.release()
        self.ctx = None

    def __enter__(self) -> "Renderer":
        return self

    def __exit__(self, *exc) -> None:
        self.release()


def render(scene: Scene, method: str = "auto", silhouettes: str = "cpu", *,
           stencil: bool = False, ctx: moderngl.Context | None = None,
           outputs: tuple[str, ...] | None = None) -> RenderResult:
    """Render one frame of `scene` (a fresh context unless `ctx` is given).  `outputs` adds to
    the default image, lit and coverage, as the command line's --outputs does (names as in
    `Renderer.render`, whose `outputs=` names exactly the arrays made, for lean frames)."""
    wanted = None if outputs is None else DEFAULT_OUTPUTS + tuple(
        o for o in check_outputs(outputs, OUTPUTS) if o not in DEFAULT_OUTPUTS)
    with Renderer(scene, ctx) as renderer:
        return renderer.render(method, silhouettes, stencil=stencil, outputs=wanted)
