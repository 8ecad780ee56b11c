"""The forward passes, kept for the planar shadows (`planar.draw`): depth and ambient for every
triangle, then per light its Phong term over the soup with depth test EQUAL, where a stencil
test passes, each handed the renderer's `pipeline.Pipeline`.  They compute the deferred
frame's numbers (see `passes`)."""

from __future__ import annotations

import moderngl
import numpy as np

from shadowvol.raster import stencil
from shadowvol.raster.glsl import set_uniform
from shadowvol.raster.passes import NO_CONE
from shadowvol.raster.projection import NEARER, in_frame
from shadowvol.scene import AreaSample, Light, SpotLight


def depth_ambient(pipe) -> None:
    """Clear everything, then depth and ambient for all triangles."""
    ctx, target, progs, scene = pipe.ctx, pipe.target, pipe.programs, pipe.scene
    target.clear(scene.background)
    ctx.enable_only(moderngl.DEPTH_TEST)
    ctx.depth_func = NEARER
    ctx.front_face = "ccw"
    set_uniform(progs.ambient, "u_ambient", tuple(float(x) for x in scene.ambient))
    progs.geometry.materials.use(0)
    set_uniform(progs.ambient, "u_materials", 0)
    # the soup's own triangles (the buffers may hold pieces of huge ones after them)
    progs.ambient_vao.render(moderngl.TRIANGLES, vertices=3 * progs.geometry.triangle_count)


def light_uniforms(program: moderngl.Program, light: Light, origin: np.ndarray) -> None:
    """A light's uniforms of the forward Phong pass, in the frame of `origin` (3,)."""
    set_uniform(program, "u_light", tuple(float(x) for x in in_frame(light.homogeneous,
                                                                       origin)))
    set_uniform(program, "u_radiance", tuple(float(x) for x in light.radiance))
    set_uniform(program, "u_emitter_cosine", 1.0 if isinstance(light, AreaSample) else 0.0)
    if isinstance(light, SpotLight):
        set_uniform(program, "u_spot_direction", tuple(float(x) for x in light.direction))
        set_uniform(program, "u_spot_cos", light.cos_cutoff)
    else:
        set_uniform(program, "u_spot_direction", (0.0, 0.0, 1.0))
        set_uniform(program, "u_spot_cos", NO_CONE)


def add_light(pipe, light: Light, stencil_test=stencil.where_unshadowed) -> None:
    """Add `light`'s Phong term where `stencil_test` passes (the shadow volumes' count is 0;
    planar shadows pass their own test); its lit mask goes to `target.lit`."""
    ctx, gl, target, progs = pipe.ctx, pipe.gl, pipe.target, pipe.programs
    target.clear_lit()
    target.use(colour=True, depth=False)
    ctx.enable_only(moderngl.DEPTH_TEST | moderngl.BLEND)
    ctx.depth_func = "=="
    ctx.blend_func = moderngl.ONE, moderngl.ONE
    ctx.blend_equation = moderngl.FUNC_ADD
    ctx.front_face = "ccw"
    light_uniforms(progs.phong, light, progs.geometry.origin)
    progs.geometry.materials.use(0)
    set_uniform(progs.phong, "u_materials", 0)
    with stencil_test(gl):
        progs.phong_vao.render(moderngl.TRIANGLES, vertices=3 * progs.geometry.triangle_count)
    ctx.enable_only(moderngl.DEPTH_TEST)
    ctx.depth_func = NEARER
    target.use()
