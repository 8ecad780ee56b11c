"""`NearGrid.candidates` in numba (the `fast` extra): the same conservative query of the short
float64 pieces a long lift skips (`raytrace.neargrid`), piece by piece instead of in numpy's
passes over all of them, which cost the masks more than the pieces' few candidates did.

The pairs are a superset of numpy's, as a set: each piece is cut in the same parts, each
part's box padded alike, each level's cells found through the same table and the boxes tested
alike; a piece that meets a level too wide, or whose box is not finite, meets that level's (or
every) triangle.  Only the order and the repeats of the pairs differ, which
`NearGrid.occluded_leaving` ignores (it asks whether any pair meets).  tests/raytrace/
test_near_grid.py holds both to the brute-force float64 test.
"""

from __future__ import annotations

import numpy as np

from .packetkernels import _jit
from .tolerances import FLOAT64_EPS


@_jit()
def _emit(out, n, piece, tri):
    """Append the pair (piece, tri) to out (2 * cap,) int64 holding n pairs, interleaved:
    (out, n + 1), out grown by doubling when full."""
    if 2 * n == out.shape[0]:
        grown = np.empty(4 * n + 128, np.int64)
        for i in range(2 * n):
            grown[i] = out[i]
        out = grown
    out[2 * n], out[2 * n + 1] = piece, tri
    return out, n + 1


@_jit()
def _left(keys, key):
    """np.searchsorted(keys, key) (side "left") of the sorted keys (n,) int64: written out,
    numba compiles numpy's own for seconds."""
    lo, hi = 0, keys.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if keys[mid] < key:
            lo = mid + 1
        else:
            hi = mid
    return lo


@_jit()
def _part(out, n, piece, lo, hi, grid):
    """The pairs of piece and the triangles whose padded boxes touch the box lo, hi (3,): at
    each level, the cells the low corners of such boxes can lie in (`NearGrid._cell_pairs`),
    or every box of the level where they are too many."""
    (cell, origin, levels, keys, starts, members, boxes, table, bits, wide_cells, hash_,
     axis_bits) = grid
    shift = np.uint64(64 - bits)
    top = float(2 ** axis_bits - 1)   # the largest cell coordinate
    c0, c1 = np.empty(3, np.int64), np.empty(3, np.int64)
    for level in levels:
        width = cell * 2.0 ** level
        count, wide = 1, False
        for a in range(3):
            c0[a] = np.int64(min(max(np.floor((lo[a] - origin[a]) / width - 1.01), 0.0), top))
            c1[a] = np.int64(min(max(np.floor((hi[a] - origin[a]) / width), -1.0), top))
            span = max(c1[a] - c0[a] + 1, 0)
            count *= span
            wide = wide or span > wide_cells
        if wide or count > wide_cells:   # every box of the level
            first = _left(keys, level << 3 * axis_bits)
            last = _left(keys, (level + 1) << 3 * axis_bits)
            out, n = _boxes(out, n, piece, lo, hi, boxes, members, starts[first], starts[last])
            continue
        for cx in range(c0[0], c1[0] + 1):
            for cy in range(c0[1], c1[1] + 1):
                for cz in range(c0[2], c1[2] + 1):
                    key = (((level << axis_bits | cx) << axis_bits | cy) << axis_bits) | cz
                    at = np.int64(table[(np.uint64(key) * hash_) >> shift])
                    if at == -2:
                        at = min(_left(keys, key), len(keys) - 1)
                    if at < 0 or keys[at] != key:
                        continue
                    out, n = _boxes(out, n, piece, lo, hi, boxes, members, starts[at],
                                    starts[at + 1])
    return out, n


@_jit()
def _boxes(out, n, piece, lo, hi, boxes, members, first, last):
    """The pairs of piece and the triangles of rows first..last-1 whose boxes touch lo, hi."""
    for row in range(first, last):
        if (boxes[0, row] <= hi[0] and boxes[3, row] >= lo[0] and boxes[1, row] <= hi[1]
                and boxes[4, row] >= lo[1] and boxes[2, row] <= hi[2]
                and boxes[5, row] >= lo[2]):
            out, n = _emit(out, n, piece, members[row])
    return out, n


@_jit()
def candidates(start, step, tmax, reach, part_cells, max_parts, always, n_faces, grid):
    """(piece (p,), triangle (p,)) int64 pairs holding every triangle that the float64 piece
    start + t·step (start, step (3, q) float64), 0 < t < tmax (q,), may meet: grid the
    `NearGrid`'s tables (`NearGrid._kernel_grid`), reach its reach, part_cells and max_parts
    `neargrid.NEAR_PART_CELLS` and `NEAR_MAX_PARTS`, always its thin triangles."""
    cell = grid[0]
    # np.int64(0), not a literal 0, which numba would compile each callee for once more
    out, n = np.empty(128 + 8 * start.shape[1], np.int64), np.int64(0)
    lo, hi, sv, dv = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    for i in range(start.shape[1]):
        s0, s1, s2 = start[0, i], start[1, i], start[2, i]
        d0, d1, d2 = step[0, i], step[1, i], step[2, i]
        length = tmax[i] * max(max(abs(d0), abs(d1)), abs(d2))
        far = max(max(abs(s0), abs(s1)), abs(s2)) + length
        parts = np.ceil(length / (part_cells * cell))
        every = (np.sqrt(s0 * s0 + s1 * s1 + s2 * s2) > reach or not parts <= max_parts
                 or not (np.isfinite(d0) and np.isfinite(d1) and np.isfinite(d2)))
        count = 1 if every else max(np.int64(parts), 1)
        slack = 8 * FLOAT64_EPS * far
        t = tmax[i] / count
        sv[0], sv[1], sv[2], dv[0], dv[1], dv[2] = s0, s1, s2, d0, d1, d2
        for j in range(0 if every else count):
            a, b = t * j, t * (j + 1)
            for axis in range(3):
                x0, x1 = sv[axis] + a * dv[axis], sv[axis] + b * dv[axis]
                lo[axis], hi[axis] = min(x0, x1) - slack, max(x0, x1) + slack
                every = every or not (np.isfinite(lo[axis]) and np.isfinite(hi[axis]))
            if every:
                break
            out, n = _part(out, n, i, lo, hi, grid)
        if every:
            for k in range(n_faces):
                out, n = _emit(out, n, i, k)
        else:
            for k in always:
                out, n = _emit(out, n, i, k)
    return out[0:2 * n:2].copy(), out[1:2 * n:2].copy()
