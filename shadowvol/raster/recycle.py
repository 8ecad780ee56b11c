"""Memory for the arrays a frame returns, reused once the caller has let go of them.

A 1280x720 frame returns about 15 MB of new arrays (the float image is 11 MB; the coverage, the
lit masks and counts the rest).  New memory is paid for at its first touch: the kernel maps and
zeroes each 4 KiB page on the first write to it, and gives the pages back when numpy frees the
array.  On this machine (a virtual machine, where each page fault also exits to the host) that
was a quarter of a 1k-triangle frame (the whole frame 45 -> 34 ms with glibc told to keep freed
memory, `benchmarks/OPTIMISATIONS.md`).

`ArrayPool.empty` hands out arrays as `np.empty` does but keeps them, and hands one out again
only when nothing but the pool refers to it.  CPython counts references, and everything that
can see an array's memory holds one to it: a view or slice of it (whose `base` it is), an array
or memoryview made from its buffer, a RenderResult that returned it.  So a render loop that
drops each frame's results before the next gets the same memory every frame, and a caller that
keeps results gets new memory; an array the caller can still reach is never written again.
"""

from __future__ import annotations

import sys

import numpy as np

# what sys.getrefcount reports for an array that only a pool's list refers to, measured the way
# `ArrayPool.empty` measures it (the count includes the call's own argument)
_kept = [np.empty(0)]
_ONLY_THE_POOL = sys.getrefcount(_kept[0])
del _kept


class ArrayPool:
    """Arrays by (shape, dtype), reused when no one else refers to them (see the module)."""

    # arrays kept per shape and dtype: the frame the caller holds, the next one, and one more
    # (a caller that writes one frame's files while the next renders)
    KEEP = 3

    def __init__(self):
        self._kept: dict[tuple, list[np.ndarray]] = {}

    def empty(self, shape, dtype) -> np.ndarray:
        """An uninitialised array of `shape` and `dtype` that nothing else refers to."""
        key = (tuple(int(n) for n in shape), np.dtype(dtype).str)
        kept = self._kept.setdefault(key, [])
        for k in range(len(kept)):
            if sys.getrefcount(kept[k]) == _ONLY_THE_POOL:
                return kept[k]
        out = np.empty(key[0], dtype)
        if len(kept) < self.KEEP:
            kept.append(out)
        return out

    def clear(self) -> None:
        """Let go of every kept array."""
        self._kept.clear()


class Scratch:
    """A renderer's own (H, W) uint32 scratch arrays, for work within one frame (0: masked
    bits, 1..: a page's bits); never returned, so reused every frame."""

    def __init__(self, height: int, width: int):
        self.height, self.width = height, width
        self._arrays: list[np.ndarray] = []

    def words(self, k: int) -> np.ndarray:
        """(H, W) uint32 scratch k."""
        while len(self._arrays) <= k:
            self._arrays.append(np.empty((self.height, self.width), np.uint32))
        return self._arrays[k]

    def bytes(self, k: int) -> np.ndarray:
        """(H, W) uint8 in the first quarter of `words(k)`'s memory."""
        h, w = self.height, self.width
        return self.words(k).reshape(-1).view(np.uint8)[:h * w].reshape(h, w)

    def clear(self) -> None:
        self._arrays.clear()
