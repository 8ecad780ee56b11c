"""The teaching overlay: exactly the shadow-volume polygons the stencil pass drew, over the frame.

Translucent and outlined, coloured by role (side quads, near caps, far caps; caps only for
casters counted with z-fail); depth-tested nearer-or-equal against the scene, so caps lying on a
surface show, and depth-clamped, so far caps at infinity are not clipped away.
"""

from __future__ import annotations

import moderngl
import numpy as np

from shadowvol.pictures import ROLE_COLOURS
from shadowvol.raster import stencil
from shadowvol.raster.passes import set_uniform
from shadowvol.raster.projection import NEARER, NEARER_OR_EQUAL
from shadowvol.scene import hard_lights

FILL_ALPHA = 0.22
LINE_ALPHA = 0.85


def draw_volume_overlay(pipe, zfail: np.ndarray) -> None:
    """Draw the volume polygons of the light `pipe.volumes` is prepared for over the target's
    colour, leaving its alpha (coverage) and the lit attachment alone."""
    ctx, gl, target, volumes = pipe.ctx, pipe.gl, pipe.target, pipe.volumes
    target.fbo.depth_mask = False
    target.fbo.color_mask = [(True, True, True, False), (False,) * 4]
    target.fbo.use()
    ctx.enable_only(moderngl.DEPTH_TEST | moderngl.BLEND)
    ctx.depth_func = NEARER_OR_EQUAL
    ctx.blend_func = moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA
    casts = volumes.geometry.casts   # the objects that cast shadows (`Object.cast_shadows`)
    all_objects = [int(i) for i in np.flatnonzero(casts)]
    capped = [int(i) for i in np.flatnonzero(zfail & casts)]
    draws = [("side", lambda: volumes.draw_sides(all_objects))]
    if capped:
        draws += [("near cap", lambda: volumes.draw_caps(capped, near=True)),
                  ("far cap", lambda: volumes.draw_caps(capped, near=False))]
    with stencil.depth_clamped(gl):
        for wireframe, alpha in ((False, FILL_ALPHA), (True, LINE_ALPHA)):
            ctx.wireframe = wireframe
            for role, draw in draws:
                for p in volumes.programs:
                    set_uniform(p, "u_colour", (*ROLE_COLOURS[role], alpha))
                draw()
    ctx.wireframe = False
    ctx.enable_only(moderngl.DEPTH_TEST)
    ctx.depth_func = NEARER
    target.use()


def draw_volume_overlays(pipe, lights, zfail: np.ndarray) -> None:
    """`draw_volume_overlay` for every hard light of `lights` (an area light: every sample)
    that casts shadows; zfail (L, n_objects) bool, the frame's method per light."""
    for i, light in enumerate(lights):
        for hard in hard_lights(light):
            if hard.shadows:
                pipe.volumes.prepare(hard.homogeneous)
                draw_volume_overlay(pipe, zfail[i])
