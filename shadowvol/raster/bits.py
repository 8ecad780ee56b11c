"""The frame's lit bits decoded into coverage, lit and lit_count.

Two layouts: a page's (H, W) uint32 bits (bit 0 covered, bit k + 1 lit by the page's hard
light k: the deferred frame's and the colour-target mask frame's), and the mask-only frame's
stencil byte (`stencil.mask_layout`: bit 7 covered, one bit per light beside the last light's
count).  Every array is written into `out`/the caller's scratch: no new memory per frame.
"""

from __future__ import annotations

import numpy as np

from shadowvol.raster import stencil
from shadowvol.raster.target import LIGHTS_PER_PAGE

# set bits of every byte (numpy < 2 has no bitwise_count)
_BYTE_BITS = np.unpackbits(np.arange(256, dtype=np.uint8)[:, None], axis=1).sum(axis=1,
                                                                                dtype=np.uint8)


def bit_count(x: np.ndarray) -> np.ndarray:
    """(H, W) uint32 -> (H, W) uint8: how many bits of each are set."""
    if hasattr(np, "bitwise_count"):
        return np.bitwise_count(x)
    b = _BYTE_BITS[np.ascontiguousarray(x).view(np.uint8)].reshape(*x.shape, 4)
    return b.sum(axis=-1, dtype=np.uint8)


def coverage(in_stencil: np.ndarray | None, pages: list[np.ndarray], masked: np.ndarray,
             out: np.ndarray) -> None:
    """`out` (H, W) bool := covered, from the stencil byte (bit 7, 0 or 1 as a bool) when
    `in_stencil` is given, else from bit 0 of the first page (`masked`: uint32 scratch)."""
    if in_stencil is not None:
        np.right_shift(in_stencil, 7, out=out.view(np.uint8))
    else:
        np.not_equal(np.bitwise_and(pages[0], np.uint32(1), out=masked), 0, out=out)


def lit_from_stencil(in_stencil: np.ndarray, hard, lit: np.ndarray, lit_count: np.ndarray,
                     byte: np.ndarray) -> None:
    """`lit`, `lit_count` (L, H, W) of a mask-only frame whose bits stayed in the stencil
    (`in_stencil` (H, W) uint8; `hard`: the frame's `pipeline.HardLight`s, hard lights only;
    `byte`: (H, W) uint8 scratch).  The lights before the last were cleared where counted;
    the last one's count is still in the low bits (0 without shadows: nothing counted)."""
    count_mask, light_bits = stencil.mask_layout(len(hard))
    for k, (h, bit) in enumerate(zip(hard, light_bits)):   # h.index == k: hard lights
        i = h.index
        last = k == len(light_bits) - 1
        np.bitwise_and(in_stencil, bit | (count_mask if last else 0), out=byte)
        np.equal(byte, bit, out=lit[i])
        lit_count[i] = lit[i]


def lit_from_pages(pages: list[np.ndarray], hard, samples: np.ndarray, lit: np.ndarray,
                   lit_count: np.ndarray, masked: np.ndarray) -> None:
    """`lit`, `lit_count` (L, H, W) from the pages' bits (LIGHTS_PER_PAGE hard lights each;
    `hard`: the frame's `pipeline.HardLight`s; `samples` (L,) int64: N per light; `masked`:
    uint32 scratch).  An area light's counts add up over its pages."""
    soft = samples > 1
    lit_count[soft] = 0
    # each light's samples in a page are neighbouring bits: one count of the set bits
    # per light and page, not one pass per sample
    masks: dict[tuple[int, int], int] = {}
    for k, h in enumerate(hard):
        page, bit = divmod(k, LIGHTS_PER_PAGE)
        masks[h.index, page] = masks.get((h.index, page), 0) | 1 << (bit + 1)
    for (i, page), mask in masks.items():
        np.bitwise_and(pages[page], np.uint32(mask), out=masked)
        if samples[i] == 1:   # a hard light: its one bit is lit, its count lit too
            np.not_equal(masked, 0, out=lit[i])
            lit_count[i] = lit[i]
        else:
            lit_count[i] += bit_count(masked)
    lit[soft] = lit_count[soft] == samples[soft, None, None]
