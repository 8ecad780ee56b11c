"""The render target: a float colour attachment, a per-light "lit" attachment, depth + stencil.

- colour (RGBA32F): linear RGB, summed over the passes (float so nothing clamps or is quantised
  before the final sRGB encoding); alpha is 1 where geometry covers the pixel.
- lit (R8): cleared before each light, set to 1 where that light's Phong term was added, i.e.
  covered, stencil 0, n . l > 0 and inside the spot cone: the light's `lit` mask.
- depth-stencil: DEPTH32F_STENCIL8, a raw-GL renderbuffer (see `stencil`: moderngl has no
  stencil API); float depth for the reversed depth of `camera.infinite_projection`.

No multisampling: every mask is sampled at pixel centres (CONVENTIONS.md).  Read-backs come out
row 0 at the top, through `camera.top_row_first`.
"""

from __future__ import annotations

import moderngl
import numpy as np

from shadowvol.raster import stencil
from shadowvol.raster.projection import FAR_DEPTH, top_row_first


class Target:
    """Owns its textures, framebuffers and renderbuffer: call `release()`."""

    def __init__(self, ctx: moderngl.Context, gl: stencil.RawGL, width: int, height: int):
        self.ctx, self.gl = ctx, gl
        self.width, self.height = width, height
        self.colour = ctx.texture((width, height), 4, dtype="f4")
        self.lit = ctx.texture((width, height), 1, dtype="f1")
        self.fbo = ctx.framebuffer(color_attachments=[self.colour, self.lit])
        self.lit_fbo = ctx.framebuffer(color_attachments=[self.lit])
        try:
            self.depth_stencil = stencil.DepthStencilBuffer(gl, self.fbo.glo, width, height)
        except Exception:
            for obj in (self.fbo, self.lit_fbo, self.colour, self.lit):
                obj.release()
            raise

    def use(self, colour: bool = True, depth: bool = True) -> None:
        """Bind for drawing with colour writes (both attachments) and depth writes on or off."""
        self.fbo.depth_mask = depth
        self.fbo.color_mask = [(colour,) * 4, (colour,) * 4]
        self.fbo.use()

    def clear(self, background: np.ndarray) -> None:
        """Colour to the background (alpha 0: not covered), lit to 0, depth to FAR_DEPTH,
        stencil 0."""
        self.use()
        self.fbo.clear(*[float(c) for c in background], 0.0)
        stencil.clear_depth_stencil(self.gl, self.fbo.glo, FAR_DEPTH)

    def clear_lit(self) -> None:
        self.lit_fbo.color_mask = (True,) * 4
        self.lit_fbo.use()
        self.lit_fbo.clear(0.0, 0.0, 0.0, 0.0)
        self.fbo.use()

    def clear_stencil(self) -> None:
        stencil.clear_stencil(self.gl, self.fbo.glo)

    def read_colour(self) -> np.ndarray:
        """(H, W, 4) float32: linear RGB and coverage alpha, row 0 at the top."""
        raw = self.fbo.read(components=4, attachment=0, dtype="f4")
        return top_row_first(np.frombuffer(raw, np.float32).reshape(self.height, self.width, 4))

    def read_lit(self) -> np.ndarray:
        """(H, W) bool, row 0 at the top."""
        raw = self.fbo.read(components=1, attachment=1, dtype="f1")
        return top_row_first(np.frombuffer(raw, np.uint8).reshape(self.height, self.width) > 127)

    def read_stencil(self) -> np.ndarray:
        """(H, W) int16: the signed stencil count (the 8-bit value read as two's complement, so
        a net -1 from DECR_WRAP reads -1), row 0 at the top."""
        raw = stencil.read_stencil(self.gl, self.fbo.glo, self.width, self.height)
        return top_row_first(raw.view(np.int8).astype(np.int16))

    def release(self) -> None:
        if self.ctx.fbo in (self.fbo, self.lit_fbo):
            # moderngl re-binds its record of the bound framebuffer after creating the next
            # one; leaving it pointing at a deleted framebuffer raises GL_INVALID_OPERATION
            self.ctx.detect_framebuffer(0).use()
        self.depth_stencil.release()
        for obj in (self.fbo, self.lit_fbo, self.colour, self.lit):
            obj.release()
