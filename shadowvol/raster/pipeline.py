"""The raster pipeline's state, named: what every pass is handed (pyrender's passes take
`(scene, flags)`; here `(pipe, frame)`).

- `Pipeline`: what a renderer draws with, made once (context, raw GL, target, programs,
  geometry) and, for a frame, the volume builder of its silhouettes (`with_volumes`).  Frozen:
  a pass reads it, never re-points it.
- `FrameState`: one frame, resolved once at the door (`FrameState.of`): the camera, the
  lights, and per hard light (an area light: each sample) its index, homogeneous position
  and method choice, with the frame's projection, z-pass clip box and culled objects.  Every
  later stop (the passes, the ground truth, the overflow check) reads it instead of
  resolving the camera and lights or choosing the method again.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import moderngl
import numpy as np

from shadowvol.raster import methods
from shadowvol.raster.geometry import SceneGeometry
from shadowvol.raster.programs import ScenePrograms
from shadowvol.raster.plan import FramePlan
from shadowvol.raster.platform.gl import RawGL
from shadowvol.raster.projection import frame_view_projection
from shadowvol.raster.target import Target
from shadowvol.raster.volumes.builder import VolumeBuilder
from shadowvol.scene import Camera, Light, Scene, hard_lights


@dataclass(frozen=True)
class Pipeline:
    """What every pass draws with: the scene (its background, ambient and objects; the
    camera and lights are the frame's) and the GL side made for it.  `volumes`: the frame's
    volume builder (None outside a frame: `with_volumes` gives the frame's pipeline)."""

    scene: Scene
    ctx: moderngl.Context
    gl: RawGL
    target: Target
    programs: ScenePrograms
    geometry: SceneGeometry
    volumes: VolumeBuilder | None = None

    @cached_property
    def stencil_export(self) -> bool:
        """The GL lets a fragment shader write the stencil (ARB_shader_stencil_export),
        looked up once."""
        return "GL_ARB_shader_stencil_export" in self.ctx.extensions

    def with_volumes(self, volumes: VolumeBuilder) -> "Pipeline":
        return replace(self, volumes=volumes)


@dataclass(frozen=True, eq=False)
class HardLight:
    """One hard light of a frame: a point, spot or directional light, or an area light's
    sample, each counted and shaded as a point light."""

    index: int            # the frame's light it is (a sample of)
    sample: int           # which sample of it (0 for a hard light)
    light: object         # the hard light itself (`shadowvol.lights.hard_lights`)
    light4: np.ndarray    # (4,) float64 homogeneous position
    zfail: np.ndarray     # (n_objects,) bool: the casters counted with z-fail (the method's)


@dataclass(frozen=True, eq=False)
class FrameState:
    """One frame's state, resolved once at the door and read by every stop after it.

    # -- what was asked ------------------------------------------------------------------
    plan       : FramePlan, the outputs and the method
    shadows    : False: no volume pass (every count 0)
    # -- the view ---------------------------------------------------------------------------
    camera     : Camera, the scene's unless overridden
    size       : (width, height) of the image
    view_proj  : (4, 4) float64 frame -> clip, in the eye's frame at `origin` (`projection`)
    origin     : (3,) float64
    zpass_box  : (6, 4) float64 `methods.zpass_clip_planes`: z-pass faces clipped to it
    clip       : zpass_box, or None when the counts are read back (`plan.want_stencil`)
    cull       : (n_objects,) bool back faces culled in the geometry pass, or None
    # -- the lights -------------------------------------------------------------------------
    lights     : tuple of Light, the scene's unless overridden
    hard       : tuple of HardLight, every hard light in the pages' order
    samples    : (L,) int64, each light's hard lights
    zfail      : (L, n_objects) bool, the casters counted with z-fail for any of its samples
    """

    plan: FramePlan
    shadows: bool
    camera: Camera
    size: tuple[int, int]
    view_proj: np.ndarray
    origin: np.ndarray
    zpass_box: np.ndarray
    clip: np.ndarray | None
    cull: np.ndarray | None
    lights: tuple[Light, ...]
    hard: tuple[HardLight, ...]
    samples: np.ndarray
    zfail: np.ndarray

    @classmethod
    def of(cls, plan: FramePlan, camera: Camera, lights: tuple[Light, ...], shadows: bool,
           geometry: SceneGeometry, size: tuple[int, int],
           outward_convex=None) -> "FrameState":
        """The frame of `camera` and `lights` (resolved: the scene's already put in) drawn
        with `geometry`; `outward_convex` (n_objects,) bool: cull those objects' back faces
        where `methods.cullable` allows (None: no culling)."""
        bounds, extent = geometry.bounds, geometry.extent
        hard = tuple(
            HardLight(i, k, sample, light4, methods.choose(plan.method, bounds, camera, size,
                                                           light4, extent))
            for i, lt in enumerate(lights) for k, sample in enumerate(hard_lights(lt))
            for light4 in (sample.homogeneous,))
        zfail = np.zeros((len(lights), len(bounds)), bool)
        for h in hard:
            zfail[h.index] |= h.zfail
        view_proj, origin = frame_view_projection(camera, size)
        box = methods.zpass_clip_planes(bounds, camera, size, extent)
        cull = (None if outward_convex is None
                else methods.cullable(bounds, outward_convex, camera, extent))
        return cls(plan=plan, shadows=shadows, camera=camera, size=size, view_proj=view_proj,
                   origin=origin, zpass_box=box, clip=None if plan.want_stencil else box,
                   cull=cull, lights=lights, hard=hard,
                   samples=np.bincount([h.index for h in hard], minlength=len(lights)
                                       ).astype(np.int64),
                   zfail=zfail)

    @property
    def hard_lights(self) -> list:
        """The hard lights themselves, in the pages' order."""
        return [h.light for h in self.hard]
