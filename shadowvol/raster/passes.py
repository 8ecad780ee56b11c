"""The passes of a shadowed frame, in order:

1. `depth_ambient`: depth (test LESS, writes on) and the ambient term ka * ambient.
2. per light (an area light: per sample, as a point light): `count_volumes` — the stencil
   cleared, then the shadow volumes drawn with colour and depth writes off and two-sided
   stencil counting, z-pass or z-fail per caster;
   `add_light` — the light's Phong term added where the stencil is 0 (depth test EQUAL, additive
   blending), and its lit mask written.

Depth is reversed (camera.NEARER is ">").  The depth test of the volume passes is "strictly
nearer", so that a volume face exactly at the surface's depth counts as behind it (z-fail near
caps tie with their own triangle; see `volumes`).
"""

from __future__ import annotations

import moderngl
import numpy as np

from shadowvol.raster import glsl, stencil
from shadowvol.raster.geometry import SceneGeometry
from shadowvol.raster.glsl import set_uniform
from shadowvol.raster.projection import NEARER, gl_matrix
from shadowvol.raster.target import Target
from shadowvol.scene import AreaSample, Camera, Light, Scene, SpotLight

NO_CONE = -2.0  # u_spot_cos for lights without a cone (below any cosine)


class ScenePrograms:
    """The programs that draw the scene's own triangles (ambient, Phong).  Call `release()`."""

    def __init__(self, ctx: moderngl.Context, geometry: SceneGeometry):
        self.geometry = geometry
        self.ambient = glsl.program(ctx, "scene.vert", "ambient.frag")
        self.phong = glsl.program(ctx, "scene.vert", "phong.frag")
        self.ambient_vao = ctx.vertex_array(self.ambient, geometry.soup_bindings(self.ambient))
        self.phong_vao = ctx.vertex_array(self.phong, geometry.soup_bindings(self.phong))

    def release(self) -> None:
        for obj in (self.ambient_vao, self.phong_vao, self.ambient, self.phong):
            obj.release()


def set_camera(programs, view_proj: np.ndarray, camera: Camera) -> None:
    for p in programs:
        set_uniform(p, "u_view_proj", gl_matrix(view_proj))
        set_uniform(p, "u_eye", tuple(float(x) for x in camera.eye))


def depth_ambient(ctx: moderngl.Context, target: Target, progs: ScenePrograms,
                  scene: Scene) -> None:
    """Clear everything, then depth and ambient for all triangles."""
    target.clear(scene.background)
    ctx.enable_only(moderngl.DEPTH_TEST)
    ctx.depth_func = NEARER
    ctx.front_face = "ccw"
    set_uniform(progs.ambient, "u_ambient", tuple(float(x) for x in scene.ambient))
    progs.geometry.materials.use(0)
    set_uniform(progs.ambient, "u_materials", 0)
    progs.ambient_vao.render(moderngl.TRIANGLES)


def count_volumes(ctx: moderngl.Context, gl: stencil.RawGL, target: Target, volumes,
                  zfail: np.ndarray, halve: bool = False,
                  clip_planes: np.ndarray | None = None, counting=None) -> None:
    """Stencil := the signed count of shadow volumes around each visible point, for the light
    `volumes` was prepared for.  zfail : (n_objects,) bool, the method per caster.

    `halve`: z-pass casters whose multiplicities are all even count half (see
    `CpuVolumes.draw_sides`): the stencil is then 0 exactly where it would have been 0, but
    the counts themselves differ.  Only for casters that z-pass counts correctly.

    `clip_planes` : (6, 4) float64 or None, the box of `methods.zpass_clip_planes`: z-pass
    side quads are clipped to it (counts at covered pixels unchanged, uncovered ones not).

    `counting(zfail, depth_clamp)` : the stencil state (a context manager from `stencil`) under
    which each group of volume faces is drawn; default: the signed count
    (`stencil.zpass_counting`, `stencil.zfail_counting`).  The stencil-overflow check draws the
    same faces under `stencil.entering_faces_counting`."""
    if counting is None:
        def counting(zfail_group: bool, depth_clamp: bool):
            return (stencil.zfail_counting(gl, depth_clamp=depth_clamp) if zfail_group
                    else stencil.zpass_counting(gl))
    target.clear_stencil()
    target.use(colour=False, depth=False)
    ctx.enable_only(moderngl.DEPTH_TEST)  # no culling: both faces count
    ctx.depth_func = NEARER
    by_zpass = [int(i) for i in np.flatnonzero(~zfail)]
    by_zfail = [int(i) for i in np.flatnonzero(zfail)]
    if by_zpass and clip_planes is not None:
        for p in volumes.programs:
            set_uniform(p, "u_clip_planes", clip_planes.astype(np.float32).tobytes())
        with counting(False, False), stencil.clip_distances(gl, len(clip_planes)):
            volumes.draw_sides(by_zpass, halve=halve, clipped=True)
    elif by_zpass:
        with counting(False, False):
            volumes.draw_sides(by_zpass, halve=halve)
    if by_zfail:
        with counting(True, True):
            volumes.draw_sides(by_zfail)
            volumes.draw_caps(by_zfail, near=False)
        with counting(True, False):
            volumes.draw_caps(by_zfail, near=True)
    target.use()


def light_uniforms(program: moderngl.Program, light: Light) -> None:
    set_uniform(program, "u_light", tuple(float(x) for x in light.homogeneous))
    set_uniform(program, "u_radiance", tuple(float(x) for x in light.radiance))
    set_uniform(program, "u_emitter_cosine", 1.0 if isinstance(light, AreaSample) else 0.0)
    if isinstance(light, SpotLight):
        set_uniform(program, "u_spot_direction", tuple(float(x) for x in light.direction))
        set_uniform(program, "u_spot_cos", light.cos_cutoff)
    else:
        set_uniform(program, "u_spot_direction", (0.0, 0.0, 1.0))
        set_uniform(program, "u_spot_cos", NO_CONE)


def add_light(ctx: moderngl.Context, gl: stencil.RawGL, target: Target, progs: ScenePrograms,
              light: Light, stencil_test=stencil.where_unshadowed) -> None:
    """Add `light`'s Phong term where `stencil_test` passes (the shadow volumes' count is 0;
    planar shadows pass their own test); its lit mask goes to `target.lit`."""
    target.clear_lit()
    target.use(colour=True, depth=False)
    ctx.enable_only(moderngl.DEPTH_TEST | moderngl.BLEND)
    ctx.depth_func = "=="
    ctx.blend_func = moderngl.ONE, moderngl.ONE
    ctx.blend_equation = moderngl.FUNC_ADD
    ctx.front_face = "ccw"
    light_uniforms(progs.phong, light)
    progs.geometry.materials.use(0)
    set_uniform(progs.phong, "u_materials", 0)
    with stencil_test(gl):
        progs.phong_vao.render(moderngl.TRIANGLES)
    ctx.enable_only(moderngl.DEPTH_TEST)
    ctx.depth_func = NEARER
    target.use()
