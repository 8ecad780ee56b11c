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
from shadowvol.raster.platform.gl import RawGL
from shadowvol.raster.passes import set_uniform
from shadowvol.raster.projection import NEARER, NEARER_OR_EQUAL

FILL_ALPHA = 0.22
LINE_ALPHA = 0.85


def draw_volume_overlay(ctx: moderngl.Context, gl: RawGL, target, volumes,
                        zfail: np.ndarray) -> None:
    """Draw the volume polygons of the light `volumes` is prepared for over `target`'s
    colour, leaving its alpha (coverage) and the lit attachment alone."""
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
