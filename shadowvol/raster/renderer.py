"""The shadow-volume renderer: `Renderer` for many frames of one scene, `render` for one.

A Renderer holds one GL context (its own, or one it is given), uploads the scene's geometry once,
and renders deferred frames: one geometry pass (depth, ambient, G-buffer), then per light the
stencil count of its shadow volumes and a full-screen pass adding its Phong term where the
count is 0 (see `passes`).  It returns arrays only, and only those asked for (`outputs=`);
files are the CLI's business.

The walk of a frame: `render` checks its arguments and resolves the frame once
(`pipeline.FrameState`: camera, lights, each hard light's position and method); the passes
(`drawing`, `passes`), the ground truth (`truth.assemble`) and the overflow check
(`overflow.detect`) each take the renderer's `pipeline.Pipeline` and that frame.

Limit: the stencil is 8 bits and counts wrap (INCR_WRAP / DECR_WRAP): 256 layers over one
pixel (about 128 closed objects, or 256 open sheets, lined up between one point and one light)
would read 0, lit.  Where conservative bounds (the scene's, then the light's) say a count could
reach 256, one more saturating volume pass finds the pixels that may have wrapped, and render()
raises overflow.detect.StencilOverflowError instead of returning a wrong shadow.
"""

from __future__ import annotations

from dataclasses import replace
from functools import cached_property

import moderngl
import numpy as np

from shadowvol.frame import LAYERS, check_light_kinds, check_outputs
from shadowvol.raster import drawing, layers, methods, overlay, passes
from shadowvol.raster.geometry import SceneGeometry
from shadowvol.raster.object_facts import ObjectFacts
from shadowvol.raster.overflow.detect import STENCIL_LIMIT, check_frame
from shadowvol.raster.overflow.policy import LightBounds
from shadowvol.raster.pipeline import FrameState, Pipeline
from shadowvol.raster.plan import FramePlan
from shadowvol.raster.platform.context import (clear_errors, create_context,
                                               errors_cleared_on_failure, make_current)
from shadowvol.raster.platform.gl import RawGL
from shadowvol.raster.programs import ScenePrograms
from shadowvol.raster.recycle import ArrayPool, Scratch
from shadowvol.raster.stencil import zero_to_one_depth
from shadowvol.raster.result import DEFAULT_OUTPUTS, OUTPUTS, RenderResult, check_lights
from shadowvol.raster.target import Target, check_frame_size
from shadowvol.raster.truth.truth_pass import TruthPass
from shadowvol.raster.volumes.builder import VolumeBuilder
from shadowvol.scene import Camera, Light, Scene


class Renderer:
    """Renders `scene` (its geometry and materials; camera and lights may change per frame).

    Use as a context manager or call `release()`: every GL object it made is released, and the
    context too if the renderer created it.
    """

    # overflow bounds (`overflow.detect.light_bound`, 0.1-0.6 s each) computed in one frame
    BOUNDS_PER_FRAME = 1

    def __init__(self, scene: Scene, ctx: moderngl.Context | None = None):
        self.scene = scene
        self._own_ctx = ctx is None
        self.ctx = create_context() if ctx is None else ctx
        self._owned = []
        self._volumes: dict[str, VolumeBuilder] = {}
        self._truth: TruthPass | None = None
        self._bounds = LightBounds()   # the overflow check's kept light bounds
        # the arrays frames return (`recycle`), and the frames' own scratch
        self._pool = ArrayPool()
        self._scratch = Scratch(scene.height, scene.width)
        # back-face culling in the geometry pass for closed convex casters beyond the near
        # plane (`methods.cullable`): 14-22% of a frame here, but OFF by default because it is
        # not exact at float32 depth ties: where a silhouette's back face won the depth test by
        # rounding, the front face shows instead (one pixel of scenes/whitted.toml)
        self.cull_back_faces = False
        # the stencil-overflow check (see `overflow`): on by default; it costs one more volume
        # pass per light, and only in scenes whose bound allows a count of 256
        self.check_overflow = True
        # a mask-only frame of up to 6 hard lights keeps its bits in the stencil where the
        # counts leave room (`drawing.masks_fit_stencil`); off: always in a colour target (the same
        # masks bit for bit: tests compare the two)
        self.masks_in_stencil = True
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
            self.programs = self._own(ScenePrograms(self.ctx, self.geometry))
            # what every pass is handed (with a frame's volume builder: `with_volumes`)
            self.pipeline = Pipeline(scene, self.ctx, self.gl, self.target, self.programs,
                                     self.geometry)
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
        methods.check_choices("auto", silhouettes)
        if silhouettes not in self._volumes:
            make_current(self.ctx)
            self._volumes[silhouettes] = self._own(
                methods.SILHOUETTE_CHOICES[silhouettes](self.ctx, self.geometry))
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
        methods.check_choices(method, silhouettes)
        outputs = set(check_outputs(outputs, OUTPUTS, DEFAULT_OUTPUTS)) | (
            {"stencil"} if stencil else set())
        wanted_layers, outputs = outputs & set(LAYERS), outputs - set(LAYERS)
        given = check_lights(lights)
        seen_by = self.scene.camera if camera is None else camera
        lit_by = self.scene.lights if given is None else given
        make_current(self.ctx)
        to_check = self._lights_to_check(seen_by, lit_by) if shadows else []
        # the overflow check needs the lit masks, asked for or not
        plan = FramePlan.of(method, outputs | ({"lit"} if to_check else set()))
        check_light_kinds(plan.outputs, lit_by)
        # the frame resolved once: every stop after this reads it (`pipeline`)
        frame = FrameState.of(plan, seen_by, lit_by, shadows, self.geometry, self.scene.size,
                              self.outward_convex if self.cull_back_faces else None)
        with errors_cleared_on_failure(self.ctx), zero_to_one_depth(self.gl):
            pipe = self.pipeline.with_volumes(self.volumes(silhouettes))
            result = drawing.draw(pipe, frame, self._pool, self._scratch,
                                  masks_in_stencil=self._masks_fit_stencil,
                                  srgb_background=lambda: self._srgb_background,
                                  truth=self._truth_pass,
                                  object_bounds=lambda: self.object_bounds)
            if to_check:
                check_frame(pipe, frame, result, only=to_check)
            if "lit" not in outputs:
                result = replace(result, lit=None, lit_count=None)
        if wanted_layers:   # the intrinsic layers: more frames (`layers`)
            result = replace(result, **layers.render_layers(
                self, method, silhouettes, camera, given, shadows, wanted_layers))
        return result

    def _lights_to_check(self, camera: Camera, lights) -> list[tuple[int, int]]:
        """(light, sample) indices of the hard lights whose stencil count might reach 256 in
        this frame: none when the scene's bound is below it, else those whose
        `overflow.detect.light_bound` is not (`overflow.policy`: at most `BOUNDS_PER_FRAME`
        bounds computed in one frame, so a frame costs at most one bound more than its
        re-checks)."""
        if not self.check_overflow or self.count_bound < STENCIL_LIMIT:
            return []
        return self._bounds.to_check(self.geometry, self.scene.height, lambda: self.convex,
                                     camera, lights, self.BOUNDS_PER_FRAME)

    _light_bounds = property(lambda self: self._bounds.kept,
                             doc="`overflow.policy.LightBounds.kept`: the light bounds kept")
    # the objects' facts (`object_facts.ObjectFacts`), each computed once, when first asked
    convex = property(lambda self: self._facts.convex,
                      doc="(n_objects,) bool: closed convex meshes")
    outward_convex = property(lambda self: self._facts.outward_convex,
                              doc="(n_objects,) bool: closed convex meshes wound outward")
    object_bounds = property(lambda self: self._facts.object_bounds,
                             doc="(n_objects,) int64: a bound on each object's own count")
    count_bound = property(lambda self: self._facts.count_bound,
                           doc="the casting objects' count bound: below 256 none can wrap")

    @cached_property
    def _srgb_background(self) -> tuple[int, int, int]:
        """The background's 8-bit sRGB code as the sRGB pass encodes it (once per renderer)."""
        return passes.srgb_code(self.pipeline, self.scene.background)

    def _truth_pass(self) -> TruthPass:
        if self._truth is None:
            self._truth = self._own(TruthPass(self.ctx, self.target))
        return self._truth

    def _masks_fit_stencil(self, frame: FrameState) -> bool:
        """`drawing.masks_fit_stencil`, never when `masks_in_stencil` is off."""
        return self.masks_in_stencil and drawing.masks_fit_stencil(
            frame, self.count_bound, self.pipeline.stencil_export)

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
        pipe = self.pipeline.with_volumes(self.volumes(silhouettes))  # the frame is left
        with zero_to_one_depth(self.gl):
            overlay.draw_volume_overlays(pipe, self.scene.lights if lights is None else lights,
                                         result.zfail)
        return np.ascontiguousarray(self.target.read_colour()[..., :3])

    def release(self) -> None:
        if self.ctx is None:
            return
        make_current(self.ctx)
        while self._owned:
            self._owned.pop().release()
        self._pool.clear()
        self._scratch.clear()
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
