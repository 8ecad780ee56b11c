"""The two ways a frame is drawn, each pass handed the `pipeline.Pipeline` and the
`pipeline.FrameState`, each returning what it made (`Drawn`):

- the mask-only frame (`mask_frame`: the lit bits and coverage alone, one page of lights): no
  G-buffer and no shading pass, its bits in a colour target or, where the counts leave room,
  in the stencil itself (`masks_fit_stencil`);
- the deferred frame (`deferred_frame`): the geometry pass, per light its count and mark, one
  shading pass per page of LIGHTS_PER_PAGE hard lights (and the facing pass for the ground
  truth).

`read_masks` decodes what either left into the frame's coverage, lit and lit_count (`bits`);
`draw` is the whole frame, from the camera set to the `RenderResult`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from shadowvol.cameras import calibration
from shadowvol.raster import bits, passes, stencil
from shadowvol.raster.recycle import ArrayPool, Scratch
from shadowvol.raster.result import RenderResult
from shadowvol.raster.target import LIGHTS_PER_PAGE
from shadowvol.raster.truth.assemble import frame_truth


@dataclass(frozen=True)
class Drawn:
    """What a frame's passes made, in the renderer's scratch (read, used and dropped within
    the frame).  pages : the lit bits of each page ((H, W) uint32, bit 0 covered, bit k + 1
    lit by the page's light k); in_stencil : the mask-only frame's stencil bytes when it kept
    its bits there, else None; truth_pages : the facing pass's (lit, facing) bits per page;
    counts : each hard light's stencil counts, when asked for."""

    pages: list = field(default_factory=list)
    in_stencil: np.ndarray | None = None
    truth_pages: list = field(default_factory=list)
    counts: list = field(default_factory=list)


def masks_fit_stencil(frame, count_bound: int, stencil_export: bool) -> bool:
    """Whether a mask-only frame keeps its bits in the stencil beside the counts
    (`stencil.mask_layout`): at most 6 lights, none an area light (whose samples' counts add
    up in lit_count), no count of the scene able to reach 2^(7 - lights) in magnitude
    (`count_bound`), and a GL that lets a fragment shader write the stencil
    (`stencil_export`: ARB_shader_stencil_export)."""
    hard = frame.hard
    if len(hard) != len(frame.lights) or not 1 <= len(hard) <= stencil.MASK_LAYOUT_LIGHTS:
        return False
    return stencil_export and (not frame.shadows or count_bound < 1 << (7 - len(hard)))


def mask_frame(pipe, frame, scratch: Scratch, in_stencil: bool = False) -> Drawn:
    """The lit bits of a mask-only frame of the frame's hard lights (one page): (H, W) uint32
    in `scratch`, bit 0 covered, bit k + 1 lit by hard light k, as the deferred frame's.  No
    G-buffer and no shading pass (`passes.mask_pass`); every light counted and its bit
    cleared where its count is not 0 in one framebuffer, so that llvmpipe bins all of them in
    one scene.

    `in_stencil` (`masks_fit_stencil`): the bits are kept in the stencil's high bits and
    each count in its low bits (`stencil.mask_layout`); the lights but the last are cleared
    where counted, the last light's count is left in place, and the stencil is returned as
    stored, (H, W) uint8 in `scratch`: no colour target, no pass after the last count, one
    byte a pixel read."""
    target, hard = pipe.target, frame.hard
    passes.mask_pass(pipe, frame, in_stencil=in_stencil)
    count_mask, light_bits = (stencil.mask_layout(len(hard)) if in_stencil else (0xFF, ()))
    for k, h in enumerate(hard):
        if frame.shadows and h.light.shadows:   # a light switched off: its bit stays facing
            pipe.volumes.prepare(h.light4)
            # the counts are 0: the mask pass cleared them, and each light's clear but the
            # last zeroes them again (`stencil.where_shadowed`)
            passes.count_signed(pipe, h.zfail, halve=frame.plan.halve, clip_planes=frame.clip,
                                receivers=True, fbo=target.mark_fbo, clear=False,
                                count_mask=count_mask)
            if not in_stencil:
                passes.clear_shadowed(pipe, k, zero=k < len(hard) - 1)
            elif k < len(hard) - 1:
                passes.clear_shadowed_in_stencil(pipe, count_mask, light_bits[k])
    if in_stencil:
        drawn = Drawn(in_stencil=target.read_stencil_bits(out=scratch.bytes(1)))
    else:
        drawn = Drawn(pages=[target.read_unshadowed(out=scratch.words(1))])
    target.use()
    return drawn


def deferred_frame(pipe, frame, scratch: Scratch, srgb_background, truth) -> Drawn:
    """The deferred frame (`passes`): the lit bits of each page of LIGHTS_PER_PAGE hard lights
    (as `mask_frame`'s; none when neither masks nor coverage are asked for and the colour
    is), the facing pass's bits per page (`truth()`: the `truth_pass.TruthPass`, asked for
    when the plan has the facing pass) and each hard light's stencil counts (when asked
    for).
    `srgb_background`: the background's sRGB code when the shading pass writes the 8-bit
    image itself, else None."""
    target, plan, hard = pipe.target, frame.plan, frame.hard
    colour = bool({"image", "image_srgb"} & plan.outputs)
    need_bits = "lit" in plan.outputs or "coverage" in plan.outputs or not colour
    # the unshadowed bits are cleared when some light of the first page is marked
    # (and always for the facing pass, which marks every light)
    passes.geometry_pass(pipe, frame.cull, marks=len(hard) > 1 or plan.facing_pass,
                         srgb_background=srgb_background)
    drawn = Drawn()
    # hard lights go in pages of LIGHTS_PER_PAGE: each one's volume count marks its
    # unshadowed bit, then one shading pass per page (one for any usual frame)
    # the stencil is all 0: the geometry pass cleared it, and each mark but a page's last
    # zeroes it again (no clear, each one a flush of llvmpipe's scene, before a count); a
    # page's last count stays for `shade`, so the next page clears it
    stencil_zero = True
    for first in range(0, max(len(hard), 1), LIGHTS_PER_PAGE):
        page = hard[first:first + LIGHTS_PER_PAGE]
        if first:
            target.clear_unshadowed()
            target.clear_lit()
        for bit, h in enumerate(page):
            if frame.shadows and h.light.shadows:
                pipe.volumes.prepare(h.light4)
                # halving is safe only for casters `auto` chose z-pass for, and only when
                # the counts themselves are not returned (see passes.count_signed)
                passes.count_signed(pipe, h.zfail, halve=plan.halve, receivers=True,
                                    clip_planes=frame.clip,
                                    # counted where it is marked: no framebuffer change
                                    # between the page's lights (llvmpipe flushes at each)
                                    fbo=None if plan.want_stencil else target.mark_fbo,
                                    clear=not stencil_zero)
                stencil_zero = False
            elif not stencil_zero:
                target.clear_stencil()
                stencil_zero = True
            if plan.want_stencil:
                drawn.counts.append(target.read_stencil())
            if bit < len(page) - 1:   # the last light's stencil is read by `shade`
                passes.mark_unshadowed(pipe, bit, restore=False, zero=True)
                stencil_zero = True
        lights = [h.light for h in page]
        passes.shade(pipe, frame.camera, lights, first_page=not first, colour=colour,
                     srgb=srgb_background is not None)
        if need_bits:   # the frame's own scratch: read, used and dropped in this frame
            drawn.pages.append(target.read_bits(out=scratch.words(len(drawn.pages) + 1)))
        if plan.facing_pass and page:
            # the facing pass reads every light's unshadowed bit: mark the last one's too
            # (the stencil still holds its count)
            passes.mark_unshadowed(pipe, len(page) - 1)
            drawn.truth_pages.append(truth().run(target, pipe.geometry, lights))
    return drawn


def read_masks(frame, drawn: Drawn, pool: ArrayPool, scratch: Scratch) -> tuple:
    """(coverage, lit, lit_count), each None unless asked for, in the pool's memory
    (`bits` decodes them)."""
    outputs, hard, samples = frame.plan.outputs, frame.hard, frame.samples
    h, w = scratch.height, scratch.width
    masked = scratch.words(0)
    coverage = lit = lit_count = None
    if "coverage" in outputs:
        coverage = pool.empty((h, w), bool)
        bits.coverage(drawn.in_stencil, drawn.pages, masked, coverage)
    if "lit" in outputs:
        lit_count = pool.empty((len(samples), h, w), np.uint16)
        lit = pool.empty((len(samples), h, w), bool)
        if drawn.in_stencil is not None:
            bits.lit_from_stencil(drawn.in_stencil, hard, lit, lit_count, scratch.bytes(0))
        else:
            bits.lit_from_pages(drawn.pages, hard, samples, lit, lit_count, masked)
    return coverage, lit, lit_count


def draw(pipe, frame, pool: ArrayPool, scratch: Scratch, *, masks_in_stencil, srgb_background,
         truth, object_bounds) -> RenderResult:
    """The frame `frame` drawn with `pipe` and read back: the `RenderResult` of what its plan
    asks for, each array from `pool` (`recycle`); numpy's temporaries go to `scratch`.  The
    renderer's lazily made parts are asked for only when the frame needs them:
    `masks_in_stencil(frame)` (`masks_fit_stencil`), `srgb_background()` (the background's
    sRGB code), `truth()` (the `truth_pass.TruthPass`) and `object_bounds()`."""
    plan, outputs = frame.plan, frame.plan.outputs
    h, w = scratch.height, scratch.width
    passes.set_frame(pipe, frame)
    # the 8-bit image straight from the shading pass when the float one is not asked for
    # and one page holds every light (pages add up in float)
    srgb_direct = ("image_srgb" in outputs and "image" not in outputs
                   and len(frame.hard) <= LIGHTS_PER_PAGE)
    if outputs <= {"lit", "coverage"} and len(frame.hard) <= LIGHTS_PER_PAGE:
        # the masks alone, one page: no G-buffer and no shading pass
        drawn = mask_frame(pipe, frame, scratch, in_stencil=masks_in_stencil(frame))
    else:
        drawn = deferred_frame(pipe, frame, scratch,
                               srgb_background() if srgb_direct else None, truth)
    image = (pipe.target.read_image(out=pool.empty((h, w, 3), np.float32))
             if "image" in outputs else None)
    coverage, lit, lit_count = read_masks(frame, drawn, pool, scratch)
    extra = frame_truth(pipe, frame, drawn.truth_pages, lambda: truth().casters, object_bounds)
    if plan.facing_pass:
        # the facing pass's lit: facing & unshadowed, bit for bit, summed over samples
        lit, counted = extra.pop("lit"), extra.pop("lit_count")
        if lit_count is not None:
            lit_count = counted
        for name in ("facing", "facing_count"):
            if name not in plan.asked:  # computed for casters only
                extra.pop(name)
    srgb = None
    if "image_srgb" in outputs:
        if not srgb_direct:   # encoded from the float image, by its own pass
            passes.encode_srgb(pipe)
        srgb = pipe.target.read_srgb(flipped=not srgb_direct,
                                     out=pool.empty((h, w, 3), np.uint8))
    return RenderResult(
        image=image, lit=lit, coverage=coverage,
        stencil=np.array(drawn.counts, np.int16).reshape(len(frame.lights), h, w)
        if plan.want_stencil else None,
        zfail=frame.zfail, lit_count=lit_count, samples=frame.samples, image_srgb=srgb,
        calibration=calibration(pipe.scene.replace(camera=frame.camera, lights=frame.lights)),
        **extra)
