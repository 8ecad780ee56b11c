"""The named stencil states, and the depth-stencil attachment: each pass's whole stencil state.

moderngl has no stencil API (moderngl#676), so the depth-stencil renderbuffer (DEPTH32F_STENCIL8),
every piece of stencil state, depth clamp, the clip-control depth range, the stencil read-back
and the colour logic op (moderngl has none either: the lit bits' OR and AND-NOT) are raw GL
calls, made here through the entry points of `gl` (the bindings); this module and `gl` are the
one raw-GL place.  Everything else — programs, buffers, textures, blending, depth test, colour
and depth write masks — stays with moderngl.

Each pass gets a context manager that sets the WHOLE stencil state it needs (test on/off, func
for both faces, ops for both faces, write mask) and restores the previous state on exit, so no pass
depends on what an earlier one left behind.
"""

from __future__ import annotations

import contextlib
import ctypes
from typing import Iterator

import numpy as np

from shadowvol.raster.platform.gl import (
    BACK_STENCIL_STATE,
    FRONT_STENCIL_STATE,
    GL_ALWAYS,
    GL_BACK,
    GL_CLIP_DEPTH_MODE,
    GL_CLIP_DISTANCE0,
    GL_CLIP_ORIGIN,
    GL_COLOR,
    GL_COLOR_LOGIC_OP,
    GL_DECR_WRAP,
    GL_DEPTH32F_STENCIL8,
    GL_DEPTH_CLAMP,
    GL_DEPTH_COMPONENT,
    GL_DEPTH_STENCIL,
    GL_DEPTH_STENCIL_ATTACHMENT,
    GL_EQUAL,
    GL_FLOAT,
    GL_FRAMEBUFFER,
    GL_FRAMEBUFFER_BINDING,
    GL_FRAMEBUFFER_COMPLETE,
    GL_FRONT,
    GL_INCR,
    GL_INCR_WRAP,
    GL_KEEP,
    GL_LOGIC_OP_MODE,
    GL_LOWER_LEFT,
    GL_NOTEQUAL,
    GL_PACK_ALIGNMENT,
    GL_RED_INTEGER,
    GL_RENDERBUFFER,
    GL_REPLACE,
    GL_RG_INTEGER,
    GL_STENCIL,
    GL_STENCIL_INDEX,
    GL_STENCIL_TEST,
    GL_UNSIGNED_BYTE,
    GL_UNSIGNED_INT,
    GL_ZERO,
    GL_ZERO_TO_ONE,
    RawGL,
    RawGLError,
)


# ---------------------------------------------------------------------------------------------
# The depth-stencil attachment
# ---------------------------------------------------------------------------------------------

class DepthStencilBuffer:
    """A DEPTH32F_STENCIL8 renderbuffer (float depth for the reversed depth of
    `camera.infinite_projection`, 8-bit stencil) attached to a moderngl framebuffer's GL object.
    Owns the renderbuffer: call `release()`."""

    def __init__(self, gl: RawGL, framebuffer_glo: int, width: int, height: int):
        self.gl = gl
        ids = (ctypes.c_uint * 1)()
        gl.glGenRenderbuffers(1, ids)
        self.glo = int(ids[0])
        gl.glBindRenderbuffer(GL_RENDERBUFFER, self.glo)
        gl.glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH32F_STENCIL8, width, height)
        gl.glBindRenderbuffer(GL_RENDERBUFFER, 0)
        with bound_framebuffer(gl, framebuffer_glo):
            gl.glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT,
                                         GL_RENDERBUFFER, self.glo)
            status = gl.glCheckFramebufferStatus(GL_FRAMEBUFFER)
        gl.check("attaching the depth-stencil renderbuffer")
        if status != GL_FRAMEBUFFER_COMPLETE:
            self.release()
            raise RawGLError(f"framebuffer incomplete (status 0x{status:04X})")

    def attach(self, framebuffer_glo: int) -> None:
        """Attach the same renderbuffer to another framebuffer too (passes that must not write
        some of the first one's attachments share its depth and stencil)."""
        with bound_framebuffer(self.gl, framebuffer_glo):
            self.gl.glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT,
                                              GL_RENDERBUFFER, self.glo)
            status = self.gl.glCheckFramebufferStatus(GL_FRAMEBUFFER)
        self.gl.check("attaching the depth-stencil renderbuffer")
        if status != GL_FRAMEBUFFER_COMPLETE:
            raise RawGLError(f"framebuffer incomplete (status 0x{status:04X})")

    def release(self) -> None:
        if self.glo:
            ids = (ctypes.c_uint * 1)(self.glo)
            self.gl.glDeleteRenderbuffers(1, ids)
            self.glo = 0


@contextlib.contextmanager
def bound_framebuffer(gl: RawGL, glo: int) -> Iterator[None]:
    previous = gl.get_int(GL_FRAMEBUFFER_BINDING)
    gl.glBindFramebuffer(GL_FRAMEBUFFER, glo)
    try:
        yield
    finally:
        gl.glBindFramebuffer(GL_FRAMEBUFFER, previous)


def clear_depth_stencil(gl: RawGL, framebuffer_glo: int, depth: float) -> None:
    """Depth to `depth`, stencil to 0 (both write masks opened for the clear, then restored)."""
    with _saved_stencil_state(gl), bound_framebuffer(gl, framebuffer_glo):
        gl.glStencilMaskSeparate(GL_FRONT, 0xFF)
        gl.glStencilMaskSeparate(GL_BACK, 0xFF)
        gl.glClearBufferfi(GL_DEPTH_STENCIL, 0, depth, 0)


def clear_stencil(gl: RawGL, framebuffer_glo: int) -> None:
    """Stencil to 0, depth untouched."""
    zero = (ctypes.c_int * 1)(0)
    with _saved_stencil_state(gl), bound_framebuffer(gl, framebuffer_glo):
        gl.glStencilMaskSeparate(GL_FRONT, 0xFF)
        gl.glStencilMaskSeparate(GL_BACK, 0xFF)
        gl.glClearBufferiv(GL_STENCIL, 0, zero)


def clear_colour_attachment(gl: RawGL, framebuffer_glo: int, draw_buffer: int,
                            value: float) -> None:
    """Float colour attachment `draw_buffer` (its index among the draw buffers) to `value` in
    every channel, under the current colour write mask (moderngl clears all attachments with
    one colour)."""
    clear_colour_attachment_values(gl, framebuffer_glo, draw_buffer, (value,) * 4)


def clear_colour_attachment_values(gl: RawGL, framebuffer_glo: int, draw_buffer: int,
                                   values) -> None:
    """Colour attachment `draw_buffer` to the 4 floats `values` (a normalised one stores
    round(255 v)), under the current colour write mask."""
    with bound_framebuffer(gl, framebuffer_glo):
        gl.glClearBufferfv(GL_COLOR, draw_buffer, (ctypes.c_float * 4)(*values))


def clear_int_attachment(gl: RawGL, framebuffer_glo: int, draw_buffer: int, value: int) -> None:
    """Integer colour attachment `draw_buffer` to `value` (glClear's float colour leaves an
    integer attachment undefined)."""
    values = (ctypes.c_int * 4)(value, value, value, value)
    with bound_framebuffer(gl, framebuffer_glo):
        gl.glClearBufferiv(GL_COLOR, draw_buffer, values)


def clear_uint_attachment(gl: RawGL, framebuffer_glo: int, draw_buffer: int,
                          value: int = 0) -> None:
    """Unsigned-integer colour attachment `draw_buffer` to `value`, under the current colour
    write mask (glClearBufferuiv: a float or signed clear leaves an unsigned one undefined)."""
    values = (ctypes.c_uint * 4)(value, value, value, value)
    with bound_framebuffer(gl, framebuffer_glo):
        gl.glClearBufferuiv(GL_COLOR, draw_buffer, values)


@contextlib.contextmanager
def logic_op(gl: RawGL, op: int) -> Iterator[None]:
    """Colour logic op `op` (GL_OR, GL_AND_INVERTED) between each fragment's output and the
    stored value, for integer colour attachments (GL applies it to integer and normalised
    ones, never to float ones); off again on exit, the op back to its previous mode."""
    previous = gl.get_int(GL_LOGIC_OP_MODE)
    gl.glLogicOp(op)
    gl.glEnable(GL_COLOR_LOGIC_OP)
    try:
        yield
    finally:
        gl.glDisable(GL_COLOR_LOGIC_OP)
        gl.glLogicOp(previous)


def clear_uint_texture(gl: RawGL, texture_glo: int, box: tuple[int, int, int, int],
                       value: int = 0, layer: int = 0, components: int = 1) -> None:
    """Texels of an unsigned-integer texture (r32ui / rg32ui; a 2D texture, or one `layer`
    of an array) to `value` (every component) in `box` (x, y, w, h, GL's rows).  moderngl
    clears only framebuffer attachments (and moderngl's Texture.write would upload them)."""
    values = (ctypes.c_uint * 4)(value, value, value, value)
    x, y, w, h = box
    gl.glClearTexSubImage(texture_glo, 0, x, y, layer, w, h, 1,
                          GL_RED_INTEGER if components == 1 else GL_RG_INTEGER,
                          GL_UNSIGNED_INT, values)


def read_stencil(gl: RawGL, framebuffer_glo: int, width: int, height: int, x: int = 0,
                 y: int = 0, out: np.ndarray | None = None) -> np.ndarray:
    """(height, width) uint8 stencil values of the rectangle whose lower-left pixel is (x, y)
    (default the whole frame), row 0 at the BOTTOM (GL order; the caller flips); into `out`
    (C-contiguous (height, width) uint8) if given."""
    if out is None:
        out = np.empty((height, width), np.uint8)
    elif out.shape != (height, width) or out.dtype != np.uint8 or not out.flags.c_contiguous:
        raise ValueError(f"out must be C-contiguous ({height}, {width}) uint8")
    previous = gl.get_int(GL_PACK_ALIGNMENT)
    with bound_framebuffer(gl, framebuffer_glo):
        gl.glPixelStorei(GL_PACK_ALIGNMENT, 1)
        gl.glReadPixels(x, y, width, height, GL_STENCIL_INDEX, GL_UNSIGNED_BYTE,
                        out.ctypes.data_as(ctypes.c_void_p))
        gl.glPixelStorei(GL_PACK_ALIGNMENT, previous)
    gl.check("reading the stencil buffer")
    return out


def read_depth(gl: RawGL, framebuffer_glo: int, width: int, height: int) -> np.ndarray:
    """(height, width) float32 depth values, row 0 at the BOTTOM (GL order; the caller flips).
    The depth attachment is DEPTH32F: the values come back as stored."""
    out = np.empty((height, width), np.float32)
    previous = gl.get_int(GL_PACK_ALIGNMENT)
    with bound_framebuffer(gl, framebuffer_glo):
        gl.glPixelStorei(GL_PACK_ALIGNMENT, 4)
        gl.glReadPixels(0, 0, width, height, GL_DEPTH_COMPONENT, GL_FLOAT,
                        out.ctypes.data_as(ctypes.c_void_p))
        gl.glPixelStorei(GL_PACK_ALIGNMENT, previous)
    gl.check("reading the depth buffer")
    return out


@contextlib.contextmanager
def zero_to_one_depth(gl: RawGL) -> Iterator[None]:
    """glClipControl(LOWER_LEFT, ZERO_TO_ONE) for a frame: clip depth 0 <= z <= w mapped to
    window depth z / w unchanged, which the reversed infinite projection needs (see camera).
    Restores the previous clip control."""
    origin, mode = gl.get_int(GL_CLIP_ORIGIN), gl.get_int(GL_CLIP_DEPTH_MODE)
    gl.glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE)
    try:
        yield
    finally:
        gl.glClipControl(origin, mode)


# ---------------------------------------------------------------------------------------------
# Stencil state for each pass
# ---------------------------------------------------------------------------------------------

@contextlib.contextmanager
def _saved_stencil_state(gl: RawGL) -> Iterator[None]:
    enabled = bool(gl.glIsEnabled(GL_STENCIL_TEST))
    clamp = bool(gl.glIsEnabled(GL_DEPTH_CLAMP))
    front = [gl.get_int(p) for p in FRONT_STENCIL_STATE]
    back = [gl.get_int(p) for p in BACK_STENCIL_STATE]
    try:
        yield
    finally:
        for face, (func, ref, vmask, sfail, zfail, zpass, wmask) in ((GL_FRONT, front),
                                                                     (GL_BACK, back)):
            gl.glStencilFuncSeparate(face, func, ref, vmask & 0xFFFFFFFF)
            gl.glStencilOpSeparate(face, sfail, zfail, zpass)
            gl.glStencilMaskSeparate(face, wmask & 0xFFFFFFFF)
        (gl.glEnable if enabled else gl.glDisable)(GL_STENCIL_TEST)
        (gl.glEnable if clamp else gl.glDisable)(GL_DEPTH_CLAMP)


def _set(gl: RawGL, *, func: int, ref: int, front_ops: tuple[int, int, int],
         back_ops: tuple[int, int, int], write_mask: int, depth_clamp: bool,
         value_mask: int = 0xFF) -> None:
    gl.glEnable(GL_STENCIL_TEST)
    for face, ops in ((GL_FRONT, front_ops), (GL_BACK, back_ops)):
        gl.glStencilFuncSeparate(face, func, ref, value_mask)
        gl.glStencilOpSeparate(face, *ops)
        gl.glStencilMaskSeparate(face, write_mask)
    (gl.glEnable if depth_clamp else gl.glDisable)(GL_DEPTH_CLAMP)


@contextlib.contextmanager
def zpass_counting(gl: RawGL, count_mask: int = 0xFF) -> Iterator[None]:
    """Z-pass: every volume face IN FRONT of the scene (depth test passes) counts, front faces
    +1, back faces -1, wrapping.  No depth clamp: geometry in front of the near plane stays
    clipped, so the count is taken from the near plane (the auto method's test relies on that).
    `count_mask`: the count is kept in these low bits only (2^k - 1: counted modulo 2^k, the
    bits above left as they are; see `mask_layout`)."""
    with _saved_stencil_state(gl):
        _set(gl, func=GL_ALWAYS, ref=0,
             front_ops=(GL_KEEP, GL_KEEP, GL_INCR_WRAP), back_ops=(GL_KEEP, GL_KEEP, GL_DECR_WRAP),
             write_mask=count_mask, depth_clamp=False)
        yield


@contextlib.contextmanager
def zfail_counting(gl: RawGL, depth_clamp: bool, count_mask: int = 0xFF) -> Iterator[None]:
    """Z-fail (Carmack's reverse): every volume face BEHIND the scene (depth test fails) counts,
    back faces +1, front faces -1, wrapping.  `depth_clamp` is on for far caps only: they lie
    exactly at depth 0 (w = 0, reversed depth) and must never be clipped away.  It is off for
    side quads, whose fragments in front of the near plane count for nothing: clamped, a side
    triangle whose plane (nearly) holds the eye is drawn through w = 0, where float32 rounding
    decides which half of the view it covers (the eye on a volume's side plane: a wedge of
    wrong counts); clipped, what is left of it lies within a sliver of its edge-on line.  Off
    too for near caps, which must be clipped exactly as the depth pass clipped the same
    triangles so that their depths tie bit for bit.  `count_mask` as in `zpass_counting`."""
    with _saved_stencil_state(gl):
        _set(gl, func=GL_ALWAYS, ref=0,
             front_ops=(GL_KEEP, GL_DECR_WRAP, GL_KEEP), back_ops=(GL_KEEP, GL_INCR_WRAP, GL_KEEP),
             write_mask=count_mask, depth_clamp=depth_clamp)
        yield


@contextlib.contextmanager
def entering_faces_counting(gl: RawGL, zfail: bool, depth_clamp: bool) -> Iterator[None]:
    """The stencil-overflow check (`shadowvol.raster.overflow.detect`): count, SATURATING at 255,
    only the volume faces by which the view ray ENTERS a volume where the count pass counts them:
    front faces in front of the surface (z-pass), back faces behind it (z-fail).  The signed count
    is at most that number, so where it stays below 255 the 8-bit signed count cannot have
    wrapped.  `depth_clamp` as in `zfail_counting`."""
    counting = (GL_KEEP, GL_INCR, GL_KEEP) if zfail else (GL_KEEP, GL_KEEP, GL_INCR)
    ignored = (GL_KEEP, GL_KEEP, GL_KEEP)
    with _saved_stencil_state(gl):
        _set(gl, func=GL_ALWAYS, ref=0, front_ops=ignored if zfail else counting,
             back_ops=counting if zfail else ignored, write_mask=0xFF,
             depth_clamp=depth_clamp)
        yield


@contextlib.contextmanager
def where_unshadowed(gl: RawGL, zero: bool = False) -> Iterator[None]:
    """Lighting: draw only where the stencil count is 0; the stencil itself is left unchanged.
    `zero`: the count of every other pixel the draw covers is set to 0 instead (the stencil
    test's fail operation, which GL applies before and whatever the depth test): after a
    full-screen draw the stencil is 0 everywhere, as a clear would leave it, without the clear
    (a flush of llvmpipe's scene)."""
    fail = GL_ZERO if zero else GL_KEEP
    with _saved_stencil_state(gl):
        _set(gl, func=GL_EQUAL, ref=0, front_ops=(fail, GL_KEEP, GL_KEEP),
             back_ops=(fail, GL_KEEP, GL_KEEP), write_mask=0xFF if zero else 0x00,
             depth_clamp=False)
        yield


@contextlib.contextmanager
def where_shadowed(gl: RawGL, zero: bool = False, count_mask: int = 0xFF,
                   also_zero: int = 0) -> Iterator[None]:
    """Draw only where the stencil count is not 0 (the complement of `where_unshadowed`); the
    stencil itself is left unchanged.  `zero`: every count the draw covers is set to 0
    instead, whatever the depth test (its pass and fail operations ZERO; a count that fails
    the stencil test is 0 already), so that after a full-screen draw the stencil is 0
    everywhere, as a clear would leave it, without the clear.

    `count_mask`: the count is these low bits only (`mask_layout`), the bits above untested
    and, unless named in `also_zero`, left as they are; with `zero`, the bits of `also_zero`
    are zeroed with the count (a mask-only frame's light bit where the light is counted)."""
    op = GL_ZERO if zero else GL_KEEP
    with _saved_stencil_state(gl):
        _set(gl, func=GL_NOTEQUAL, ref=0, value_mask=count_mask,
             front_ops=(GL_KEEP, op, op), back_ops=(GL_KEEP, op, op),
             write_mask=count_mask | also_zero if zero else 0x00, depth_clamp=False)
        yield


@contextlib.contextmanager
def zeroed_counts(gl: RawGL, count_mask: int = 0xFF) -> Iterator[None]:
    """After a light's count, the objects that receive no shadow (`Object.receive_shadows`)
    drawn again with the depth test EQUAL: where one is the visible surface, its count (the
    bits of `count_mask`) := 0, unshadowed, either face."""
    put = (GL_KEEP, GL_KEEP, GL_ZERO)
    with _saved_stencil_state(gl):
        _set(gl, func=GL_ALWAYS, ref=0, front_ops=put, back_ops=put, write_mask=count_mask,
             depth_clamp=False)
        yield


# A mask-only frame of a few hard lights keeps its bits in the stencil itself, beside the
# counts, where the scene's counts fit (`Renderer._masks_fit_stencil`): no colour target, no
# clear pass after the last light, one byte a pixel read back.

MASK_LAYOUT_LIGHTS = 6   # the most lights whose bits fit beside a count (of 1 bit at least)


def mask_layout(lights: int) -> tuple[int, tuple[int, ...]]:
    """The stencil byte of a mask-only frame of `lights` (1..MASK_LAYOUT_LIGHTS) hard lights
    kept in the stencil: bit 7 covered, bit 6 - i "the visible side faces light i"
    (shade.frag's lit bits reversed: STENCIL_BITS), and the low 7 - `lights` bits the light's
    count, modulo 2^(7 - lights): exact where no count's magnitude reaches that.  (count mask,
    light i's bit for each i)."""
    if not 1 <= lights <= MASK_LAYOUT_LIGHTS:
        raise ValueError(f"1..{MASK_LAYOUT_LIGHTS} lights fit in the stencil beside a count, "
                         f"got {lights}")
    return (1 << (7 - lights)) - 1, tuple(0x40 >> i for i in range(lights))


@contextlib.contextmanager
def _written_where_drawn(gl: RawGL, ref: int, depth_clamp: bool = False) -> Iterator[None]:
    """Every fragment that passes the depth test (either face) writes `ref`, or the value its
    shader exports (gl_FragStencilRefARB), into the whole stencil byte."""
    put = (GL_KEEP, GL_KEEP, GL_REPLACE)
    with _saved_stencil_state(gl):
        _set(gl, func=GL_ALWAYS, ref=ref, front_ops=put, back_ops=put, write_mask=0xFF,
             depth_clamp=depth_clamp)
        yield


def exported_bits(gl: RawGL) -> contextlib.AbstractContextManager[None]:
    """The mask pass with the bits in the stencil: every fragment that passes the depth test
    writes the whole stencil byte its shader exports (`mask_layout`, the counts' bits 0), as a
    colour write would have written the bits."""
    return _written_where_drawn(gl, 0)


def caster_touching(gl: RawGL, depth_clamp: bool) -> contextlib.AbstractContextManager[None]:
    """The ground truth's per-caster counts (`truth.truth_pass.CasterCounts`), which go to an
    image: the stencil := 1 wherever a counted fragment lands (either face; the image counts the
    fragments that pass the depth test, z-fail's under the complementary test), so a pixel
    whose counters are not all 0 has stencil 1.  `depth_clamp` as `zpass_counting` (off)
    and `zfail_counting` take it for the same faces."""
    return _written_where_drawn(gl, 1, depth_clamp)


@contextlib.contextmanager
def depth_clamped(gl: RawGL) -> Iterator[None]:
    """No stencil, depth clamp on: for drawing shadow polygons in the teaching view, where the
    far caps at infinity must survive clipping."""
    with _saved_stencil_state(gl):
        gl.glDisable(GL_STENCIL_TEST)
        gl.glEnable(GL_DEPTH_CLAMP)
        yield


# ---------------------------------------------------------------------------------------------
# Planar projected shadows (shadowvol.raster.planar.draw): mark the receiver, shadow each pixel
# once, light where not shadowed
# ---------------------------------------------------------------------------------------------

PLANAR_RECEIVER = 1   # stencil value of a pixel where the receiving plane is the visible surface
PLANAR_SHADOW = 2     # ... and where a projected shadow covers it


def planar_receiver_mark(gl: RawGL) -> contextlib.AbstractContextManager[None]:
    """Every fragment that passes the depth test writes PLANAR_RECEIVER (drawn with the
    receiver's own triangles and depth test EQUAL: its visible pixels).  Projected shadows are
    later drawn only there, so none hangs off the receiver's edge or lands on another object."""
    return _written_where_drawn(gl, PLANAR_RECEIVER)


@contextlib.contextmanager
def planar_shadow_once(gl: RawGL) -> Iterator[None]:
    """Draw a projected shadow fragment only where the stencil is PLANAR_RECEIVER and raise it
    to PLANAR_SHADOW: the first shadow triangle over a pixel marks it, every later one (the
    projections overlap: a closed caster projects its front and its back) fails the test, so
    no pixel is shadowed twice."""
    with _saved_stencil_state(gl):
        _set(gl, func=GL_EQUAL, ref=PLANAR_RECEIVER,
             front_ops=(GL_KEEP, GL_KEEP, GL_INCR), back_ops=(GL_KEEP, GL_KEEP, GL_INCR),
             write_mask=0xFF, depth_clamp=False)
        yield


@contextlib.contextmanager
def where_not_planar_shadow(gl: RawGL) -> Iterator[None]:
    """Lighting with projected shadows: draw wherever the stencil is not PLANAR_SHADOW (the
    rest of the receiver and every other object); the stencil is left unchanged."""
    with _saved_stencil_state(gl):
        _set(gl, func=GL_NOTEQUAL, ref=PLANAR_SHADOW, front_ops=(GL_KEEP, GL_KEEP, GL_KEEP),
             back_ops=(GL_KEEP, GL_KEEP, GL_KEEP), write_mask=0x00, depth_clamp=False)
        yield


@contextlib.contextmanager
def clip_distances(gl: RawGL, count: int) -> Iterator[None]:
    """GL_CLIP_DISTANCE0 .. count - 1 enabled (moderngl has no switch for them); all disabled
    again on exit.  Shaders that write gl_ClipDistance are clipped only while enabled."""
    for i in range(count):
        gl.glEnable(GL_CLIP_DISTANCE0 + i)
    try:
        yield
    finally:
        for i in range(count):
            gl.glDisable(GL_CLIP_DISTANCE0 + i)
