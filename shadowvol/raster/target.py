"""The render target: the G-buffer of the deferred frame, depth + stencil, and the read-backs.

- position (RGBA32F), written by the geometry pass: the visible surface's world position, and
  in w +-(triangle index + 1), negative where its back face is seen, 0 where nothing is drawn:
  the key of the per-triangle data (normal, first corner, object; a float, exact below 2^24).
  Further per-pixel outputs (depth, object id) fit beside it as attachments of the same pass.
- uv (RG32F) and tint (RGBA32F), only in a scene with textures or vertex colours (`surface`),
  written by the geometry pass beside position: the visible surface's interpolated UVs and
  vertex colour, which the shading pass turns into its base colour (docs/CONVENTIONS.md,
  "Textures").
- unshadowed (R32UI): bit i set where light i's stencil count was 0 (the mark pass ORs it in:
  a colour logic op).  A mask-only frame uses it for its lit bits instead (bits as in `bits`,
  set by its geometry pass and cleared per light by the logic op AND-NOT: `passes.mask_pass`),
  read back once by `read_unshadowed`.
- colour (RGBA32F): linear RGB (float so nothing clamps or is quantised before the final sRGB
  encoding); alpha is 1 where geometry covers the pixel.
- bits (R32F): bit 0 covered, bit i + 1 lit by the frame's i-th light (of a page of
  `LIGHTS_PER_PAGE`): every light's lit mask and the coverage come back in ONE read.  (The
  forward passes, the planar shadows', clear it per light and add 1.0: one light's mask.)
- depth-stencil: DEPTH32F_STENCIL8, a raw-GL renderbuffer (see `stencil`: moderngl has no
  stencil API) shared by every framebuffer here; float depth for the reversed depth of
  `camera.infinite_projection`.
- srgb (RGBA8): the image encoded to 8-bit sRGB, either by a full-screen pass over colour
  (`srgb_fbo`, rows flipped) or, when the frame is one page and the float image is not asked
  for, by the shading pass itself (`srgb_shade_fbo`: srgb and bits, with the depth-stencil;
  GL's row order), which then writes no float colour at all.

A pass never samples a texture attached to the framebuffer it draws into (undefined in GL), so
each pass has its framebuffer: `gbuffer_fbo`, `mark_fbo`, `fbo` (colour and bits), `srgb_fbo`,
`srgb_shade_fbo`.
No multisampling: every mask is sampled at pixel centres (CONVENTIONS.md).  Read-backs go into
buffers allocated once and come out row 0 at the top (one flip, here, or none for the sRGB
image, whose pass writes the rows flipped).
"""

from __future__ import annotations

import moderngl
import numpy as np

from shadowvol.errors import RenderError
from shadowvol.raster import stencil
from shadowvol.raster.platform.gl import RawGL, RawGLError
from shadowvol.raster.projection import FAR_DEPTH
from shadowvol.scene import SceneError

LIGHTS_PER_PAGE = 23  # lit bits 1..23 and the coverage bit of a float32: exact


# GPU memory of one pixel of the frame: colour RGBA32F, lit bits R32F, G-buffer RGBA32F,
# unshadowed marks R32UI, sRGB RGBA8, depth32F + stencil8 (8 with padding)
BYTES_PER_PIXEL = 16 + 4 + 16 + 4 + 4 + 8
# and the G-buffer's uv RG32F and tint RGBA32F of a scene with textures or vertex colours
SURFACE_BYTES_PER_PIXEL = 8 + 16


# the attributes a Target owns (what `release` frees, also after a failed allocation)
_TEXTURES = ("colour", "bits", "position", "unshadowed", "srgb", "uv", "tint")
_FRAMEBUFFERS = ("gbuffer_fbo", "mark_fbo", "fbo", "lit_fbo", "srgb_fbo", "srgb_shade_fbo")


def _flipped(staging: np.ndarray, out: np.ndarray | None, dtype=None) -> np.ndarray:
    """A read-back's staging (GL's row order, bottom row first) with row 0 at the top: into
    `out` if given, else into a new array of `dtype` (default the staging's)."""
    if out is None:
        out = np.empty(staging.shape, staging.dtype if dtype is None else dtype)
    np.copyto(out, staging[::-1], casting="unsafe")
    return out


def max_side(ctx: moderngl.Context) -> int:
    """The widest or tallest frame this GL can make: its textures', renderbuffers' and
    viewport's limits, the least of them."""
    info = ctx.info
    return min(info["GL_MAX_RENDERBUFFER_SIZE"], info["GL_MAX_TEXTURE_SIZE"],
               *info.get("GL_MAX_VIEWPORT_DIMS", ()))


def check_frame_size(ctx: moderngl.Context, width: int, height: int) -> None:
    """SceneError (`image`, bad input) for a frame wider or taller than this GL allows (a
    limit of the input, not a failure of the GL), before anything is allocated."""
    limit = max_side(ctx)
    if max(width, height) > limit:
        raise SceneError("image", f"{width}x{height} is larger than this GL allows ({limit} "
                                  "pixels per side)")


class FrameAllocationError(RenderError):
    """The GL could not allocate the frame's buffers (out of GPU memory, or a size the driver
    refuses)."""


class Target:
    """Owns its textures, framebuffers and renderbuffer: call `release()`."""

    def __init__(self, ctx: moderngl.Context, gl: RawGL, width: int, height: int,
                 surface: bool = False):
        self.ctx, self.gl = ctx, gl
        self._textures, self._fbos, self.depth_stencil = (), (), None
        self.surface = surface   # the G-buffer holds uv and tint too
        try:
            self._allocate(ctx, gl, width, height)
        except (moderngl.Error, RawGLError) as exc:
            self.release()
            mib = width * height * (BYTES_PER_PIXEL + surface * SURFACE_BYTES_PER_PIXEL) / 2**20
            raise FrameAllocationError(
                f"the GL could not allocate a {width}x{height} frame (about {mib:,.0f} MiB of "
                f"GPU memory at {BYTES_PER_PIXEL} bytes a pixel; {exc}); try a smaller "
                "image") from None

    def _allocate(self, ctx: moderngl.Context, gl: RawGL, width: int,
                  height: int) -> None:
        self.ctx, self.gl = ctx, gl
        self.width, self.height = width, height
        self.colour = ctx.texture((width, height), 4, dtype="f4")
        self.bits = ctx.texture((width, height), 1, dtype="f4")
        self.position = ctx.texture((width, height), 4, dtype="f4")
        self.unshadowed = ctx.texture((width, height), 1, dtype="u4")
        self.srgb = ctx.texture((width, height), 4, dtype="f1")
        self._textures = (self.colour, self.bits, self.position, self.unshadowed, self.srgb)
        gbuffer = [self.position]
        if self.surface:
            self.uv = ctx.texture((width, height), 2, dtype="f4")
            self.tint = ctx.texture((width, height), 4, dtype="f4")
            self._textures += (self.uv, self.tint)
            gbuffer += [self.uv, self.tint]
        for t in self._textures:
            t.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self.gbuffer_fbo = ctx.framebuffer(color_attachments=gbuffer)
        self.mark_fbo = ctx.framebuffer(color_attachments=[self.unshadowed])
        self.fbo = ctx.framebuffer(color_attachments=[self.colour, self.bits])
        self.lit_fbo = ctx.framebuffer(color_attachments=[self.bits])
        self.srgb_fbo = ctx.framebuffer(color_attachments=[self.srgb])
        self.srgb_shade_fbo = ctx.framebuffer(color_attachments=[self.srgb, self.bits])
        self._fbos = (self.gbuffer_fbo, self.mark_fbo, self.fbo, self.lit_fbo, self.srgb_fbo,
                      self.srgb_shade_fbo)
        # read-back staging, GL's row order (bottom row first), allocated once
        self._rgba = np.empty((height, width, 4), np.float32)
        self._rgb = np.empty((height, width, 3), np.float32)
        self._bits = np.empty((height, width), np.float32)
        self._unshadowed = np.empty((height, width), np.uint32)
        self._srgb8 = np.empty((height, width, 3), np.uint8)
        self._stencil8 = np.empty((height, width), np.uint8)
        try:
            self.depth_stencil = stencil.DepthStencilBuffer(gl, self.fbo.glo, width, height)
            self.depth_stencil.attach(self.gbuffer_fbo.glo)
            self.depth_stencil.attach(self.mark_fbo.glo)
            self.depth_stencil.attach(self.srgb_shade_fbo.glo)
        except Exception:
            for obj in (*self._fbos, *self._textures):
                obj.release()
            raise

    def use(self, colour: bool = True, depth: bool = True) -> None:
        """Bind for drawing with colour writes (colour and bits) and depth writes on or off."""
        self.fbo.depth_mask = depth
        self.fbo.color_mask = [(colour,) * 4, (colour,) * 4]
        self.fbo.use()

    def use_gbuffer(self) -> None:
        """Bind the geometry pass's framebuffer: position (and surface) and depth written."""
        self.gbuffer_fbo.depth_mask = True
        self.gbuffer_fbo.color_mask = [(True,) * 4] * 3 if self.surface else (True,) * 4
        self.gbuffer_fbo.use()

    def clear(self, background: np.ndarray) -> None:
        """For the forward passes: colour to the background (alpha 0: not covered), bits to 0,
        depth to FAR_DEPTH, stencil 0; `fbo` left bound."""
        self.use()
        self.fbo.clear(*[float(c) for c in background], 0.0)
        stencil.clear_depth_stencil(self.gl, self.fbo.glo, FAR_DEPTH)
        stencil.clear_colour_attachment(self.gl, self.fbo.glo, 1, 0.0)

    def clear_gbuffer(self, background: np.ndarray, marks: bool) -> None:
        """For the geometry pass: colour to the background (alpha 0), bits to 0, depth to
        FAR_DEPTH, stencil 0, and the unshadowed bits to 0 if `marks` (a light will be
        marked).  The full-screen passes run only where geometry is (depth test), so these are
        what uncovered pixels keep, and the position attachment needs no clear: it is read
        only where the geometry pass has just written it."""
        self.clear(background)   # colour, bits, depth, stencil (`fbo`)
        if marks:
            self.clear_unshadowed()  # glClearBuffer: moderngl's clear would clear the depth

    def clear_unshadowed(self) -> None:
        self.mark_fbo.color_mask = (True,) * 4
        stencil.clear_uint_attachment(self.gl, self.mark_fbo.glo, 0, 0)

    def clear_lit(self) -> None:
        self.lit_fbo.color_mask = (True,) * 4
        self.lit_fbo.use()
        self.lit_fbo.clear(0.0, 0.0, 0.0, 0.0)
        self.fbo.use()

    def clear_stencil(self) -> None:
        stencil.clear_stencil(self.gl, self.fbo.glo)

    def read_colour(self) -> np.ndarray:
        """(H, W, 4) float32: linear RGB and coverage alpha, row 0 at the top."""
        self.fbo.read_into(self._rgba, components=4, attachment=0, dtype="f4")
        return np.ascontiguousarray(self._rgba[::-1])

    def read_image(self, out: np.ndarray | None = None) -> np.ndarray:
        """(H, W, 3) float32 linear RGB, row 0 at the top, into `out` if given (GL packs RGB;
        one contiguous copy flips the rows: a strided numpy copy of RGB out of RGBA costs 5x
        more)."""
        self.fbo.read_into(self._rgb, components=3, attachment=0, dtype="f4")
        return _flipped(self._rgb, out)

    def read_bits(self, out: np.ndarray | None = None) -> np.ndarray:
        """(H, W) uint32 of the bits attachment, row 0 at the top, into `out` if given."""
        self.fbo.read_into(self._bits, components=1, attachment=1, dtype="f4")
        return _flipped(self._bits, out, np.uint32)   # integers below 2^24: exact

    def read_unshadowed(self, out: np.ndarray | None = None) -> np.ndarray:
        """(H, W) uint32 of the unshadowed attachment (a mask-only frame's lit bits), row 0 at
        the top, into `out` if given."""
        self.mark_fbo.read_into(self._unshadowed, components=1, attachment=0, dtype="u4")
        return _flipped(self._unshadowed, out)

    def read_stencil_bits(self, out: np.ndarray | None = None) -> np.ndarray:
        """(H, W) uint8 of the stencil as stored, row 0 at the top, into `out` if given: a
        mask-only frame's bits and last count when it keeps them there
        (`stencil.mask_layout`)."""
        stencil.read_stencil(self.gl, self.mark_fbo.glo, self.width, self.height,
                             out=self._stencil8)
        return _flipped(self._stencil8, out)

    def read_lit(self) -> np.ndarray:
        """(H, W) bool, row 0 at the top: the one light of a forward lighting pass."""
        return self.read_bits() > 0

    def read_srgb(self, flipped: bool = True, out: np.ndarray | None = None) -> np.ndarray:
        """(H, W, 3) uint8 sRGB, row 0 at the top, into `out` if given: `flipped`, as the sRGB
        pass writes it (the rows already flipped), else in GL's order (the shading pass's),
        flipped here."""
        if not flipped:
            self.srgb_fbo.read_into(self._srgb8, components=3, attachment=0, dtype="f1")
            return _flipped(self._srgb8, out)
        if out is None:
            out = np.empty((self.height, self.width, 3), np.uint8)
        self.srgb_fbo.read_into(out, components=3, attachment=0, dtype="f1")
        return out

    def clear_srgb(self, code) -> None:
        """The srgb attachment to the 8-bit code (3,) in every pixel (alpha 255): what the
        shading pass leaves where no geometry is."""
        self.srgb_shade_fbo.color_mask = [(True,) * 4, (True,) * 4]
        value = [int(c) / 255.0 for c in code] + [1.0]
        stencil.clear_colour_attachment_values(self.gl, self.srgb_shade_fbo.glo, 0, value)

    def read_stencil(self) -> np.ndarray:
        """(H, W) int16: the signed stencil count (the 8-bit value read as two's complement, so
        a net -1 from DECR_WRAP reads -1), row 0 at the top."""
        raw = stencil.read_stencil(self.gl, self.fbo.glo, self.width, self.height)
        return np.ascontiguousarray(raw[::-1]).view(np.int8).astype(np.int16)

    def release(self) -> None:
        # what a failed allocation made so far is released too
        made = [getattr(self, n, None) for n in _TEXTURES + _FRAMEBUFFERS]
        self._textures = tuple(o for o in made[:len(_TEXTURES)] if o is not None)
        self._fbos = tuple(o for o in made[len(_TEXTURES):] if o is not None)
        if self.ctx.fbo in self._fbos:
            # moderngl re-binds its record of the bound framebuffer after creating the next
            # one; leaving it pointing at a deleted framebuffer raises GL_INVALID_OPERATION
            self.ctx.detect_framebuffer(0).use()
        if self.depth_stencil is not None:
            self.depth_stencil.release()
        for obj in (*self._fbos, *self._textures):
            obj.release()
        for name in _TEXTURES + _FRAMEBUFFERS:
            if hasattr(self, name):
                delattr(self, name)
        self._textures, self._fbos, self.depth_stencil = (), (), None
