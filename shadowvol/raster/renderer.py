"""The shadow-volume renderer: `Renderer` for many frames of one scene, `render` for one.

A Renderer holds one GL context (its own, or one it is given), uploads the scene's geometry once,
and renders frames: depth + ambient, then per light the stencil count of its shadow volumes and
its Phong term where the count is 0.  It returns arrays only; files are the CLI's business.

Limit: the stencil is 8 bits and counts wrap (INCR_WRAP / DECR_WRAP).  Every triangle casts, so
a pixel behind k closed meshes counts 2k; 256 layers over one pixel would read 0, i.e. lit.  That
needs about 128 closed objects (or 256 open sheets) lined up between one point and one light.
It is detected (`overflow`): when a conservative bound says a count could reach 256, one more
saturating volume pass per light finds the pixels that may have wrapped, and render() raises
overflow.StencilOverflowError instead of returning a wrong shadow.
"""

from __future__ import annotations

from dataclasses import dataclass

import moderngl
import numpy as np

from shadowvol.raster import methods, overflow, overlay, passes
from shadowvol.raster import stencil as stencil_gl
from shadowvol.raster.context import create_context, make_current
from shadowvol.raster.geometry import SceneGeometry
from shadowvol.raster.projection import view_projection
from shadowvol.raster.target import Target
from shadowvol.raster.volumes import CpuVolumes, GpuVolumes
from shadowvol.scene import (
    AreaLight,
    Camera,
    DirectionalLight,
    Light,
    PointLight,
    Scene,
    SpotLight,
    hard_lights,
)

SILHOUETTES = ("cpu", "gpu")


@dataclass(frozen=True, eq=False)
class RenderResult:
    """One frame.

    image    : (H, W, 3) float32 linear RGB (direct Phong lighting; an area light's samples
               summed: soft shadows)
    lit      : (L, H, W) bool, per light: covered, stencil 0, n . l > 0, inside the spot cone;
               for an area light: so for every sample (lit_count == N)
    coverage : (H, W) bool, geometry visible at the pixel centre
    stencil  : (L, H, W) int16 signed stencil counts after each light's volume pass, or None
               when not asked for (hard lights only)
    zfail    : (L, n_objects) bool, which casters were counted with z-fail for each light
               (for an area light: for any of its samples)
    lit_count : (L, H, W) uint16, per light how many of its samples (hard lights: 1) light the
               pixel as `lit` says
    samples  : (L,) int64, N per light (hard lights: 1)
    """

    image: np.ndarray
    lit: np.ndarray
    coverage: np.ndarray
    stencil: np.ndarray | None
    zfail: np.ndarray
    lit_count: np.ndarray
    samples: np.ndarray

    @property
    def visibility(self) -> np.ndarray:
        """(L, H, W) float32: lit_count / N."""
        return (self.lit_count / self.samples[:, None, None]).astype(np.float32)

    @property
    def penumbra(self) -> np.ndarray:
        """(L, H, W) bool: some samples light the pixel, not all (0 < lit_count < N)."""
        return (self.lit_count > 0) & ~self.lit

    def _repr_png_(self) -> bytes:
        """A notebook shows the frame as its image."""
        from shadowvol.display import frame_png
        return frame_png(self)


class Renderer:
    """Renders `scene` (its geometry and materials; camera and lights may change per frame).

    Use as a context manager or call `release()`: every GL object it made is released, and the
    context too if the renderer created it.
    """

    def __init__(self, scene: Scene, ctx: moderngl.Context | None = None):
        self.scene = scene
        self._own_ctx = ctx is None
        self.ctx = create_context() if ctx is None else ctx
        self._owned = []
        self._volumes: dict[str, CpuVolumes | GpuVolumes] = {}
        self._count_bound: int | None = None
        # the stencil-overflow check (see `overflow`): on by default; it costs one more volume
        # pass per light, and only in scenes whose bound allows a count of 256
        self.check_overflow = True
        try:
            # every public method first makes the context current: raw GL calls
            # (stencil.RawGL) go to whichever context is current, e.g. after another renderer
            # with its own context has run
            make_current(self.ctx)
            self.gl = stencil_gl.RawGL()
            self.geometry = self._own(SceneGeometry(self.ctx, scene))
            self.target = self._own(Target(self.ctx, self.gl, scene.width, scene.height))
            self.programs = self._own(passes.ScenePrograms(self.ctx, self.geometry))
        except BaseException:
            self.release()
            raise

    def _own(self, obj):
        self._owned.append(obj)
        return obj

    def volumes(self, silhouettes: str) -> CpuVolumes | GpuVolumes:
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
               stencil: bool = False, shadows: bool = True) -> RenderResult:
        """One frame.  `method`: "auto" (z-fail only for casters the near plane may cut),
        "zpass" or "zfail".  `camera`/`lights` override the scene's for this frame.
        `stencil=True` also returns the per-light stencil counts (one extra read-back each).
        `shadows=False` skips the volume passes (every count stays 0): the same frame without
        shadows, the benchmark's baseline."""
        if method not in methods.METHODS:
            raise ValueError(f"method must be one of {', '.join(methods.METHODS)}, "
                             f"got {method!r}")
        lights = _check_lights(lights)
        make_current(self.ctx)
        with stencil_gl.zero_to_one_depth(self.gl):
            result = self._render(method, silhouettes, camera, lights, stencil, shadows)
            if shadows and self.check_overflow and self.count_bound >= overflow.STENCIL_LIMIT:
                overflow.check_frame(self, result, silhouettes, camera, lights,
                                     halve=method == "auto" and not stencil)
            return result

    @property
    def count_bound(self) -> int:
        """`overflow.count_bound` of the scene: below 256 no stencil count can wrap."""
        if self._count_bound is None:
            self._count_bound = overflow.count_bound(self.geometry.topologies)
        return self._count_bound

    def _render(self, method, silhouettes, camera, lights, stencil, shadows) -> RenderResult:
        camera = self.scene.camera if camera is None else camera
        lights = self.scene.lights if lights is None else tuple(lights)
        vols = self.volumes(silhouettes)
        view_proj = view_projection(camera, self.scene.aspect)
        passes.set_camera((self.programs.ambient, self.programs.phong, *vols.programs),
                          view_proj, camera)
        passes.depth_ambient(self.ctx, self.target, self.programs, self.scene)
        # z-pass faces clipped to the box of the near rectangle and the casters: the same
        # counts at covered pixels, not at uncovered ones (see methods.zpass_clip_planes)
        clip = None if stencil else methods.zpass_clip_planes(
            self.geometry.bounds, camera, self.scene.aspect, self.geometry.extent)
        h, w = self.scene.height, self.scene.width
        if stencil and any(isinstance(light, AreaLight) for light in lights):
            raise ValueError("stencil counts are per hard light: not for area lights")
        lit_count = np.zeros((len(lights), h, w), np.uint16)
        zfail = np.zeros((len(lights), len(self.scene.objects)), bool)
        counts = []
        # an area light is its samples, each counted and shaded as a point light
        for i, sample in ((i, hard) for i, lt in enumerate(lights) for hard in hard_lights(lt)):
            light4 = sample.homogeneous
            choice = methods.choose(method, self.geometry.bounds, camera, self.scene.aspect,
                                    light4, self.geometry.extent)
            if shadows:
                vols.prepare(light4)
                # halving is safe only for casters `auto` chose z-pass for, and only when
                # the counts themselves are not returned (see passes.count_volumes)
                passes.count_volumes(self.ctx, self.gl, self.target, vols, choice,
                                     halve=method == "auto" and not stencil, clip_planes=clip)
            else:
                self.target.clear_stencil()
            if stencil:
                counts.append(self.target.read_stencil())
            passes.add_light(self.ctx, self.gl, self.target, self.programs, sample)
            lit_count[i] += self.target.read_lit()
            zfail[i] |= choice
        rgba = self.target.read_colour()
        samples = np.array([len(hard_lights(lt)) for lt in lights], np.int64)
        return RenderResult(
            image=np.ascontiguousarray(rgba[..., :3]),
            lit=lit_count == samples[:, None, None],
            coverage=rgba[..., 3] > 0.5,
            stencil=np.array(counts, np.int16).reshape(len(lights), h, w) if stencil else None,
            zfail=zfail, lit_count=lit_count, samples=samples)

    def facing(self, *, camera: Camera | None = None,
               lights: tuple[Light, ...] | None = None) -> np.ndarray:
        """(L, H, W) bool: some sample of each light faces the pixel (n . l > 0 toward it and
        inside its cone), shadows aside: the frame without the volume passes.  With a
        frame's `lit_count`, umbra = facing & (lit_count == 0)."""
        return self.render(camera=camera, lights=lights, shadows=False).lit_count > 0

    def volume_view(self, method: str = "auto", silhouettes: str = "cpu", *,
                    camera: Camera | None = None,
                    lights: tuple[Light, ...] | None = None) -> np.ndarray:
        """(H, W, 3) float32 linear RGB: the frame lit by `lights` (default: the scene's, as in
        `render`) with their shadow-volume polygons drawn over it, coloured by role (see
        `overlay`).  The polygons are exactly those the stencil pass drew under `method`."""
        lights = _check_lights(lights)
        result = self.render(method, silhouettes, camera=camera, lights=lights)
        vols = self.volumes(silhouettes)  # the frame is left in the target
        with stencil_gl.zero_to_one_depth(self.gl):
            for i, light in ((i, hard) for i, lt in enumerate(self.scene.lights if lights is None
                                                              else lights)
                             for hard in hard_lights(lt)):  # an area light: every sample's
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
        if self._own_ctx:
            self.ctx.release()
        self.ctx = None

    def __enter__(self) -> "Renderer":
        return self

    def __exit__(self, *exc) -> None:
        self.release()


def _check_lights(lights) -> tuple[Light, ...] | None:
    """`lights=` of render and volume_view: None (the scene's) or Light objects; anything else
    (light indices, say) is a TypeError rather than a frame without those lights."""
    if lights is None:
        return None
    lights = tuple(lights)
    bad = [x for x in lights
           if not isinstance(x, (PointLight, DirectionalLight, SpotLight, AreaLight))]
    if bad:
        raise TypeError(f"lights must be Light objects (e.g. scene.lights[0]), got {bad[0]!r}")
    return lights


def render(scene: Scene, method: str = "auto", silhouettes: str = "cpu", *,
           stencil: bool = False, ctx: moderngl.Context | None = None) -> RenderResult:
    """Render one frame of `scene` (a fresh context unless `ctx` is given)."""
    with Renderer(scene, ctx) as renderer:
        return renderer.render(method, silhouettes, stencil=stencil)
