"""`ScenePrograms`: the programs that draw the scene's own triangles, made once per renderer
(the geometry pass, the marks, the shading and sRGB passes, the mask pass, the forward passes
of the planar shadows), for the passes of `passes`."""

from __future__ import annotations

import moderngl
import numpy as np

from shadowvol.raster import glsl
from shadowvol.raster.geometry import SceneGeometry


class ScenePrograms:
    """The programs that draw the scene's own triangles: the geometry pass and the deferred
    lighting and sRGB passes; the forward ambient and Phong passes over the soup (planar
    shadows) on first use.  Call `release()`."""

    def __init__(self, ctx: moderngl.Context, geometry: SceneGeometry):
        self.ctx, self.geometry = ctx, geometry
        # textures or vertex colours: UVs and colours in the G-buffer (SURFACE)
        self.surface = {"SURFACE": 1} if geometry.surface else {}
        self.gbuffer = glsl.program(ctx, "scene.vert", "gbuffer.frag", defines=self.surface)
        self.gbuffer_vao = ctx.vertex_array(self.gbuffer, geometry.soup_bindings(self.gbuffer))
        self.mark = glsl.program(ctx, "fullscreen.vert", "mark.frag")
        self.mark_vao = ctx.vertex_array(self.mark, [])
        # (lights, colour, sRGB out, spot lights, emitter lights) -> program, vao
        self._shade: dict[tuple[int, bool, bool, int, int], tuple] = {}
        # (lights, spot lights, bits in the stencil) -> program, vao of the mask pass
        self._masks: dict[tuple[int, int, bool], tuple] = {}
        self.srgb = glsl.program(ctx, "fullscreen.vert", "srgb.frag")
        self.srgb_vao = ctx.vertex_array(self.srgb, [])
        self._forward = None
        # the objects that receive no shadow, drawn again after each count (`count_signed`)
        self.unreceiving = np.flatnonzero(~geometry.receives)
        self.receivers = glsl.program(ctx, "scene.vert", "volume.frag") \
            if len(self.unreceiving) else None
        self.receivers_vao = None if self.receivers is None else ctx.vertex_array(
            self.receivers, geometry.soup_bindings(self.receivers))

    def shading(self, lights: int, colour: bool, srgb: bool = False, spots: int = 0,
                emitters: int = 0) -> tuple:
        """(program, vao) of the shading pass for a page of `lights` lights (a constant in the
        shader: its loop unrolls), with colour or the lit bits only, the colour as linear
        float or (`srgb`) encoded to 8-bit sRGB; `spots`, `emitters`: bit i set where light i
        is a spot light, an area light's sample (constants too: see shade.frag); made on first
        use."""
        key = (lights, colour, srgb, spots, emitters)
        if key not in self._shade:
            defines = ({"LIGHTS": lights, "SPOT_LIGHTS": spots, "EMITTER_LIGHTS": emitters} |
                       ({} if colour else {"MASKS_ONLY": 1}) |
                       ({"SRGB_OUT": 1} if srgb else {}) | (self.surface if colour else {}))
            program = glsl.program(self.ctx, "fullscreen.vert", "shade.frag", defines=defines)
            self._shade[key] = (program, self.ctx.vertex_array(program, []))
        return self._shade[key]

    def mask_pass(self, lights: int, spots: int, in_stencil: bool = False) -> tuple:
        """(program, vao) of a mask-only frame's geometry pass for a page of `lights` lights,
        bit i of `spots` set where light i is a spot (shade.frag's MASK_PASS), writing its
        bits into the stencil if `in_stencil` (STENCIL_BITS); made on first use."""
        key = (lights, spots, in_stencil)
        if key not in self._masks:
            program = glsl.program(self.ctx, "scene.vert", "shade.frag", defines={
                "LIGHTS": lights, "SPOT_LIGHTS": spots, "MASKS_ONLY": 1, "MASK_PASS": 1} |
                ({"STENCIL_BITS": 1} if in_stencil else {}))
            self._masks[key] = (program, self.ctx.vertex_array(
                program, self.geometry.soup_bindings(program)))
        return self._masks[key]

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

    @property
    def framed(self) -> tuple[moderngl.Program, ...]:
        """The programs that take the frame's camera (`set_camera`) with the volumes'."""
        return (self.gbuffer,) + (() if self.receivers is None else (self.receivers,))

    def release(self) -> None:
        for obj in (self.gbuffer_vao, self.mark_vao, self.srgb_vao, self.gbuffer, self.mark,
                    *((self.receivers_vao, self.receivers) if self.receivers else ()),
                    self.srgb, *(x for pv in self._shade.values() for x in pv[::-1]),
                    *(x for pv in self._masks.values() for x in pv[::-1]),
                    *(self._forward or ())):
            obj.release()
