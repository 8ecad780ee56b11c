"""The passes of a shadowed frame (deferred: the scene's triangles are drawn once), in order:

1. `geometry_pass`: one indexed draw of every triangle: depth (test NEARER, writes on), the
   ambient term ka * ambient, the coverage bit and the G-buffer (world position, triangle).
2. per light: `count_volumes` — the stencil cleared, then the shadow volumes drawn with colour
   and depth writes off and two-sided stencil counting, z-pass or z-fail per caster;
   `shade_light` — a full-screen pass adding the light's Phong term where the stencil is 0
   (additive blending) and its lit bit.
3. `encode_srgb`, when the 8-bit image is asked for.

The forward passes (`depth_ambient`, then per light `add_light` over the soup with depth test
EQUAL) remain for the planar shadows.  Both compute the same numbers: the same depths (same
vertex shader, invariant, same vertices in the same order) and the same lighting expressions
on the same float32 inputs (phong.frag, with or without DEFERRED).

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
from shadowvol.scene import Camera, Light, Scene, SpotLight

NO_CONE = -2.0  # u_spot_cos for lights without a cone (below any cosine)


class ScenePrograms:
    """The programs that draw the scene's own triangles: the geometry pass and the deferred
    lighting and sRGB passes; the forward ambient and Phong passes over the soup (planar
    shadows) on first use.  Call `release()`."""

    def __init__(self, ctx: moderngl.Context, geometry: SceneGeometry):
        self.ctx, self.geometry = ctx, geometry
        self.gbuffer = glsl.program(ctx, "scene.vert", "gbuffer.frag")
        self.gbuffer_vao = ctx.vertex_array(self.gbuffer, geometry.mesh_bindings(self.gbuffer),
                                            index_buffer=geometry.mesh_indices,
                                            index_element_size=4)
        self.shade = glsl.program(ctx, "fullscreen.vert", "phong.frag",
                                  defines={"DEFERRED": 1})
        self.shade_vao = ctx.vertex_array(self.shade, [])
        self.srgb = glsl.program(ctx, "fullscreen.vert", "srgb.frag")
        self.srgb_vao = ctx.vertex_array(self.srgb, [])
        self._forward = None

    def _forward_programs(self):
        if self._forward is None:
            ambient = glsl.program(self.ctx, "scene.vert", "ambient.frag")
            phong = glsl.program(self.ctx, "scene.vert", "phong.frag")
            self._forward = (ambient, phong,
                             self.ctx.vertex_array(ambient, self.geometry.soup_bindings(ambient)),
                             self.ctx.vertex_array(phong, self.geometry.soup_bindings(phong)))
        return self._forward

    @property
    def ambient(self) -> moderngl.Program:
        return self._forward_programs()[0]

    @property
    def phong(self) -> moderngl.Program:
        return self._forward_programs()[1]

    @property
    def ambient_vao(self) -> moderngl.VertexArray:
        return self._forward_programs()[2]

    @property
    def phong_vao(self) -> moderngl.VertexArray:
        return self._forward_programs()[3]

    def release(self) -> None:
        for obj in (self.gbuffer_vao, self.shade_vao, self.srgb_vao, self.gbuffer, self.shade,
                    self.srgb, *(self._forward or ())):
            obj.release()


def set_camera(programs, view_proj: np.ndarray, camera: Camera) -> None:
    for p in programs:
        set_uniform(p, "u_view_proj", gl_matrix(view_proj))
        set_uniform(p, "u_eye", tuple(float(x) for x in camera.eye))


def geometry_pass(ctx: moderngl.Context, target: Target, progs: ScenePrograms,
                  scene: Scene) -> None:
    """Clear everything, then one indexed draw of all triangles: depth, ambient, coverage and
    the G-buffer."""
    target.clear(scene.background)
    target.use_gbuffer()
    ctx.enable_only(moderngl.DEPTH_TEST)
    ctx.depth_func = NEARER
    ctx.front_face = "ccw"
    set_uniform(progs.gbuffer, "u_ambient", tuple(float(x) for x in scene.ambient))
    progs.geometry.materials.use(0)
    set_uniform(progs.gbuffer, "u_materials", 0)
    progs.gbuffer_vao.render(moderngl.TRIANGLES)
    target.use()


def shade_light(ctx: moderngl.Context, gl: stencil.RawGL, target: Target, progs: ScenePrograms,
                light: Light, bit: int) -> None:
    """Add `light`'s Phong term where the stencil count is 0, and 2^bit to the bits
    attachment there (a full-screen pass over the G-buffer; no depth test: every pixel's
    surface is the geometry pass's)."""
    target.use(colour=True, depth=False)
    ctx.enable_only(moderngl.BLEND)
    ctx.blend_func = moderngl.ONE, moderngl.ONE
    ctx.blend_equation = moderngl.FUNC_ADD
    prog = progs.shade
    light_uniforms(prog, light)
    set_uniform(prog, "u_bit", float(2 ** bit))
    progs.geometry.materials.use(0)
    target.position.use(1)
    target.surface.use(2)
    set_uniform(prog, "u_materials", 0)
    set_uniform(prog, "u_position", 1)
    set_uniform(prog, "u_surface", 2)
    progs.geometry.triangle_data.bind_to_storage_buffer(0)
    with stencil.where_unshadowed(gl):
        progs.shade_vao.render(moderngl.TRIANGLES, vertices=3)
    ctx.enable_only(moderngl.DEPTH_TEST)
    ctx.depth_func = NEARER


def encode_srgb(ctx: moderngl.Context, target: Target, progs: ScenePrograms) -> None:
    """The colour attachment encoded to 8-bit sRGB into `target.srgb`, rows flipped."""
    target.srgb_fbo.use()
    ctx.enable_only(moderngl.NOTHING)
    target.colour.use(0)
    set_uniform(progs.srgb, "u_colour", 0)
    progs.srgb_vao.render(moderngl.TRIANGLES, vertices=3)
    ctx.enable_only(moderngl.DEPTH_TEST)
    target.use()


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
