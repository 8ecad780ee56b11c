"""The float64 test of the short pieces a long lift skips, on the few triangles near them.

`TriangleBackend.occluded_leaving` asks, for a short segment leaving a surface at p, whether
any triangle other than p's own (and those whose plane passes through p) meets it in float64
(`raytrace.tolerances`, item 3b).  Walking a float64 BVH for every such piece cost the masks
more than all their Embree rays.  Here a loose grid of padded triangle boxes answers first
the conservative question -- which triangles' boxes the piece's box touches (almost always
none, or p's neighbours) -- and the float64 test of the walk (`intersect.ray_triangle`, the
same exclusions) runs on those pairs only.

Conservative: every triangle on which `ray_triangle` may report a hit at 0 < λ < tmax is a
candidate.  The computed hit point lies on the piece (up to its own rounding, which pads the
piece's box) and within the triangle's pad of the triangle: the float64 error of λ (off the
plane) and of the barycentric test (in it) grows as 1 / sin² of the triangle's angle at its
first corner, so each box is padded by `tolerances.NEAR_BOX_ERROR_ULPS` spacings of the
scene's reach over that sin² (above 1 / SLIVER_SHAPE² at every corner of a triangle that is
not a sliver; computed for slivers); a triangle too thin for that bound
(`tolerances.NEAR_SLIVER_SIN2`) is a candidate of every piece, one whose cross product is
exactly zero (it never meets a ray: n·r = 0) of none.  A long piece is cut into parts a few
cells long; a piece that starts beyond the reach the pads assume, would need too many parts
or is not finite is tested against every triangle.  `tests/raytrace/test_near_grid.py`
checks the candidates against a brute-force float64 test and the answers against the walk.
"""

from __future__ import annotations

import numpy as np

from .intersect import dot, ray_triangle
from .tolerances import (
    FLOAT64_EPS,
    NEAR_BOX_ERROR_ULPS,
    NEAR_SLIVER_SIN2,
    SLIVER_SHAPE,
    error_weight,
    plane_error64,
)

# Tuning (speed only, never results): the finest cell, in median extents of the triangles'
# boxes (from at most NEAR_CELL_SAMPLE of them); pairs tested at once (bounds the temporaries).
NEAR_CELL_EXTENTS = 1.0
NEAR_CELL_SAMPLE = 4096
NEAR_PAIRS_PER_BATCH = 1 << 16
# A piece whose box spans more than NEAR_PIECE_CELLS cells of a level meets that level's boxes
# one by one.
NEAR_PIECE_CELLS = 64
# A piece is cut in parts no longer (along any axis) than NEAR_PART_CELLS finest cells, in at
# most NEAR_MAX_PARTS (a longer one meets every triangle).
NEAR_PART_CELLS = 2.0
NEAR_MAX_PARTS = 1 << 14
# A cell key packs the level (LEVEL_BITS) and three cell coordinates (AXIS_BITS each).
LEVEL_BITS, AXIS_BITS = 6, 19
# The table finding a key's cell has at least NEAR_TABLE_SLOTS slots per occupied cell (a
# power of two, int32: at most 32 bytes a cell; a key is looked for in the sorted keys only
# where its slot is shared).
NEAR_TABLE_SLOTS = 4
_HASH = np.uint64(0x9E3779B97F4A7C15)  # Fibonacci hashing: the top bits of key · 2**64/φ


def _expand(counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For counts (n,) >= 0: owner (sum,) int64, the index repeated counts[i] times, and rank
    (sum,) int64, 0 .. counts[i] - 1 within each."""
    owner = np.repeat(np.arange(len(counts)), counts)
    first = np.cumsum(counts) - counts
    return owner, np.arange(len(owner)) - first[owner]


def _dot3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot products of component-major vectors (3, n) x (3, n) -> (n,)."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


class NearGrid:
    """The padded boxes of triangles (vertices (N, 3) float64, faces (M, 3) int64, fragile (M,)
    bool: `tolerances.is_sliver`) in a loose grid of levels (vectors component-major, (3, M)):
    a box of extent at most cell·2**level is registered once, at that level, in the cell
    holding its low corner, so a box [lo, hi] can touch only the level's boxes whose low
    corners lie in [lo − cell·2**level, hi] (cells are numbered by a monotone function of the
    coordinates).  `occluded_leaving` tests short float64 segments against the triangles
    whose boxes theirs touch."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, fragile: np.ndarray):
        v = np.ascontiguousarray(np.asarray(vertices, dtype=np.float64).T)
        f = np.asarray(faces, dtype=np.int64)
        a, b, c = (np.take(v, f[:, i], axis=1) for i in range(3))
        self.vertices, self.faces = v, f  # the corners of candidates, gathered when tested
        # the reach: a bound of |x| (Euclidean) of every corner and of the pieces' starts
        self.reach = float(np.sqrt(3.0) * np.abs(v).max()) if v.size else 0.0
        # sin² of the first corner's angle: above 1 / SLIVER_SHAPE² unless `fragile` (the
        # angle between the two longest edges is the largest but one); half that, for the
        # rounding of is_sliver's test
        sin2 = np.full(len(f), 0.5 / SLIVER_SHAPE ** 2)
        live = np.ones(len(f), bool)
        k = np.flatnonzero(fragile)
        e1, e2 = b[:, k] - a[:, k], c[:, k] - a[:, k]
        # n = e1 x e2 as ray_triangle computes it (np.cross): exactly zero never meets a ray
        n = np.stack([e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                      e1[0] * e2[1] - e1[1] * e2[0]])
        live[k] = (n[0] != 0.0) | (n[1] != 0.0) | (n[2] != 0.0)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
            sin2[k] = np.minimum(_dot3(n, n) / (_dot3(e1, e1) * _dot3(e2, e2)), sin2[k])
        thin = live & ~(sin2 >= NEAR_SLIVER_SIN2)  # NaN: thin too
        self.always = np.flatnonzero(thin)
        boxed = np.flatnonzero(live & ~thin)
        pad = NEAR_BOX_ERROR_ULPS * FLOAT64_EPS * self.reach / sin2[boxed]
        if len(boxed) < len(f):
            a, b, c = a[:, boxed], b[:, boxed], c[:, boxed]
        self.boxed = boxed
        self._grid(np.minimum(np.minimum(a, b), c) - pad, np.maximum(np.maximum(a, b), c) + pad)

    def _grid(self, lo: np.ndarray, hi: np.ndarray) -> None:
        """Each boxed triangle's level and cell (its box lo, hi (3, m)): keys (k,) the occupied
        cells' keys, sorted; members, the triangles by cell, boxes (6, m) their boxes (lo, hi);
        starts (k + 1,) where each cell's begin; levels, the levels in use."""
        m = lo.shape[1]
        self.origin, self.cell = np.zeros(3), 1.0
        self.levels, self.keys, self.members = (np.zeros(0, np.int64),) * 3
        self.boxes = np.zeros((6, 0))
        self.starts = np.zeros(1, np.int64)
        self._bits, self._table = 10, np.full(1 << 10, -1, np.int32)
        if m == 0:
            return
        size = hi - lo
        extent = np.maximum(np.maximum(size[0], size[1]), size[2])
        self.origin = lo.min(axis=1)
        span = float((hi.max(axis=1) - self.origin).max())
        sample = extent[::max(1, m // NEAR_CELL_SAMPLE)]
        # the finest cell; every cell coordinate of every level below 2**AXIS_BITS
        self.cell = max(NEAR_CELL_EXTENTS * float(np.median(sample)),
                        2.0 * span / 2 ** AXIS_BITS, 1e-300)
        # the least level with extent <= cell·2**level: x = f·2**e, f in [0.5, 1), is at most
        # 2**e, and at most 2**(e - 1) where f == 0.5
        f, e = np.frexp(np.maximum(extent / self.cell, 1.0))
        level = np.minimum(e - (f == 0.5), 2 ** LEVEL_BITS - 1).astype(np.int64)
        width = np.ldexp(self.cell, level)
        keys = self._key(level, np.floor((lo - self.origin[:, None]) / width).astype(np.int64))
        order = np.argsort(keys)
        keys, self.members = keys[order], self.boxed[order]
        # the boxes in cell order, component-major (lo, hi): a cell's boxes are read in one run
        self.boxes = np.take(np.concatenate([lo, hi]), order, axis=1)
        new = np.flatnonzero(np.diff(keys, prepend=-1))
        self.keys, self.starts = keys[new], np.append(new, len(keys))
        self.levels = np.flatnonzero(np.bincount(level))
        self._index(max(10, (NEAR_TABLE_SLOTS * len(new) - 1).bit_length()))

    def _index(self, bits: int) -> None:
        """The table of 2**bits slots: slot -> the cell whose key alone lands there, -2 where
        several do, -1 none (a slot that several keys share keeps one, and each other marks
        it)."""
        self._bits = bits
        slot, cell = self._slot(self.keys), np.arange(len(self.keys), dtype=np.int32)
        self._table = np.full(1 << bits, -1, np.int32)
        self._table[slot] = cell
        self._table[slot[self._table[slot] != cell]] = -2

    def _slot(self, keys: np.ndarray) -> np.ndarray:
        """The table's slot (n,) of each key (n,) int64."""
        return ((keys.view(np.uint64) * _HASH) >> np.uint64(64 - self._bits)).astype(np.int64)

    def _find(self, keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(found, at): the keys (n,) that are occupied cells' (their indices into keys) and
        those cells' indices into self.keys."""
        at = self._table[self._slot(keys)].astype(np.int64)
        shared = np.flatnonzero(at == -2)
        at[shared] = np.minimum(np.searchsorted(self.keys, keys[shared]), len(self.keys) - 1)
        found = np.flatnonzero(at >= 0)
        found = found[self.keys[at[found]] == keys[found]]
        return found, at[found]

    @staticmethod
    def _key(level: np.ndarray, c: np.ndarray) -> np.ndarray:
        """The key of cell c (3, n) int64 (each 0 <= c < 2**AXIS_BITS) of level (n,)."""
        return (((level << AXIS_BITS | c[0]) << AXIS_BITS | c[1]) << AXIS_BITS) | c[2]

    def pairs(self, lo: np.ndarray, hi: np.ndarray, everything: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
        """(piece, triangle) int64 pairs, (p,) each (a pair may repeat): the triangles whose
        padded boxes touch the boxes [lo, hi] (3, q), the thin ones, and every triangle for
        the pieces where `everything` (q,) bool."""
        every = np.flatnonzero(everything)
        piece, k = _expand(np.full(len(every), len(self.faces)))
        out = [(every[piece], k)]
        rest = np.flatnonzero(~everything)
        out.append(self._cell_pairs(rest, lo[:, rest], hi[:, rest]))
        if len(self.always):
            piece, k = _expand(np.full(len(rest), len(self.always)))
            out.append((rest[piece], self.always[k]))
        return np.concatenate([p for p, _ in out]), np.concatenate([t for _, t in out])

    def _cell_pairs(self, pieces, lo, hi):
        """Pairs of pieces (p,) and the triangles whose boxes touch theirs, lo, hi (3, p):
        at each level in use, the cells the low corners of such boxes can lie in (widened by
        1 % against rounding), kept where the boxes overlap."""
        if len(self.keys) == 0 or len(pieces) == 0:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        level = np.repeat(self.levels, len(pieces))
        which = np.tile(np.arange(len(pieces)), len(self.levels))
        width = np.ldexp(self.cell, level)
        top = 2 ** AXIS_BITS - 1
        with np.errstate(invalid="ignore", over="ignore"):
            c0 = np.floor((lo[:, which] - self.origin[:, None]) / width - 1.01)
            c1 = np.floor((hi[:, which] - self.origin[:, None]) / width)
        c0 = np.clip(c0, 0, top).astype(np.int64)
        c1 = np.clip(c1, -1, top).astype(np.int64)
        n = np.maximum(c1 - c0 + 1, 0)
        # a long piece spans many cells: it meets the level's boxes one by one instead
        wide = (n > NEAR_PIECE_CELLS).any(axis=0)
        count = np.where(wide, 0, n[0] * n[1] * n[2])
        wide |= count > NEAR_PIECE_CELLS
        count[wide] = 0
        found = [self._level_pairs(pieces, lo, hi, level[w], which[w])
                 for w in np.flatnonzero(wide)]
        # the keys of each block: its first cell's plus the offsets, one axis at a time (no
        # carries: every coordinate of the block is below 2**AXIS_BITS)
        owner = np.flatnonzero(count)
        keys = self._key(level[owner], c0[:, owner])
        for axis in (2, 1, 0):
            at, rank = _expand(n[axis, owner])
            owner, keys = owner[at], keys[at] + (rank << (2 - axis) * AXIS_BITS)
        hit, at = self._find(keys)
        owner = owner[hit]
        start = self.starts[at]
        cell, rank = _expand(self.starts[at + 1] - start)
        row, j = start[cell] + rank, which[owner[cell]]
        # the boxes overlap: axis by axis, each test on the pairs the last one kept
        for i in range(3):
            keep = np.flatnonzero((self.boxes[i, row] <= hi[i, j]) &
                                  (self.boxes[3 + i, row] >= lo[i, j]))
            row, j = row[keep], j[keep]
        found.append((pieces[j], self.members[row]))
        return np.concatenate([p for p, _ in found]), np.concatenate([t for _, t in found])

    def _level_pairs(self, pieces, lo, hi, level: int, j: int):
        """The pairs of piece j and every triangle of `level` whose box touches its box."""
        first, last = np.searchsorted(self.keys, [level << 3 * AXIS_BITS,
                                                  (level + 1) << 3 * AXIS_BITS])
        box = self.boxes[:, self.starts[first]:self.starts[last]]
        touch = ((box[:3] <= hi[:, j, None]) & (box[3:] >= lo[:, j, None])).all(axis=0)
        return (np.full(int(touch.sum()), pieces[j]),
                self.members[self.starts[first]:self.starts[last]][touch])

    def candidates(self, origins: np.ndarray, directions: np.ndarray, tmax: np.ndarray,
                   compiled: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """(piece, triangle) int64 pairs, (p,) each (a pair may repeat), that hold every
        triangle on which `intersect.ray_triangle` may meet the float64 piece origins +
        t·directions, 0 < t < tmax: origins, directions (n, 3) float64, tmax (n,) > 0.
        compiled: by `raytrace.nearkernels` where numba loads (the same pairs, as a set),
        else (or False) in numpy."""
        kernels = _kernels() if compiled else None
        if kernels is not None:
            start = np.ascontiguousarray(np.asarray(origins, dtype=np.float64).T)
            step = np.ascontiguousarray(np.asarray(directions, dtype=np.float64).T)
            return kernels.candidates(start, step, np.asarray(tmax, dtype=np.float64),
                                      self.reach, NEAR_PART_CELLS, NEAR_MAX_PARTS,
                                      self.always, len(self.faces), self._kernel_grid())
        return self._numpy_candidates(origins, directions, tmax)

    def _kernel_grid(self) -> tuple:
        """The grid's tables as `nearkernels.candidates` takes them."""
        return (float(self.cell), self.origin, self.levels, self.keys, self.starts,
                self.members, np.ascontiguousarray(self.boxes), self._table, self._bits,
                NEAR_PIECE_CELLS, _HASH, AXIS_BITS)

    def _numpy_candidates(self, origins, directions, tmax) -> tuple[np.ndarray, np.ndarray]:
        """`candidates` in numpy."""
        # Each piece in parts of at most NEAR_PART_CELLS finest cells (a long one's box would
        # span a whole level's cells); a part's box padded by a bound of the rounding of its
        # computed end points (|o| + tmax·|d| bounds every |x| along the piece).
        start = np.ascontiguousarray(np.asarray(origins, dtype=np.float64).T)
        step = np.ascontiguousarray(np.asarray(directions, dtype=np.float64).T)
        tmax = np.asarray(tmax, dtype=np.float64)
        length = tmax * np.abs(step).max(axis=0)
        reach = np.abs(start).max(axis=0) + length
        with np.errstate(invalid="ignore", over="ignore"):
            parts = np.ceil(length / (NEAR_PART_CELLS * self.cell))
        # the pads assume |origin| <= reach; a piece too long to cut, or not finite, meets all
        everything = ((np.sqrt(_dot3(start, start)) > self.reach) | ~(parts <= NEAR_MAX_PARTS)
                      | ~np.isfinite(step).all(axis=0))
        parts = np.where(everything, 1, np.maximum(parts, 1)).astype(np.int64)
        which, j = _expand(parts)
        t = tmax[which] / parts[which]
        x0 = start[:, which] + (t * j) * step[:, which]
        x1 = start[:, which] + (t * (j + 1)) * step[:, which]
        slack = 8 * FLOAT64_EPS * reach[which]
        with np.errstate(invalid="ignore"):
            lo = np.minimum(x0, x1) - slack
            hi = np.maximum(x0, x1) + slack
        part, tri = self.pairs(lo, hi, everything[which])
        return which[part], tri

    def occluded_leaving(self, triangles, origins, directions, tmax, own) -> np.ndarray:
        """`TriangleBackend.occluded_leaving` for the triangles of this grid: (n,) bool, does
        the float64 ray origins + t·directions (n, 3; directions may be (1, 3)) meet, at
        0 < t < tmax (n,), a triangle other than own (n,) int64 and those whose plane passes
        through the origin up to `tolerances.plane_error64`?  triangles: the `TriangleSet`
        (normals, plane_d) the grid was built from."""
        o = np.asarray(origins, dtype=np.float64)
        d = np.broadcast_to(np.asarray(directions, dtype=np.float64), o.shape)
        tmax = np.broadcast_to(np.asarray(tmax, dtype=np.float64), (len(o),))
        own = np.asarray(own, dtype=np.int64)
        blocked = np.zeros(len(o), bool)
        go = np.flatnonzero(tmax > 0.0)
        if len(go) == 0 or len(self.faces) == 0:
            return blocked
        piece, tri = self.candidates(o[go], d[go], tmax[go])
        piece = go[piece]
        for s in range(0, len(piece), NEAR_PAIRS_PER_BATCH):
            p, k = piece[s:s + NEAR_PAIRS_PER_BATCH], tri[s:s + NEAR_PAIRS_PER_BATCH]
            p, k = p[~blocked[p]], k[~blocked[p]]
            hit = _pair_hits(triangles, self, o[p], d[p], tmax[p], k, own[p])
            blocked[p[hit]] = True
        return blocked


def _kernels():
    """`raytrace.nearkernels`, or None where numba is missing."""
    try:
        from . import nearkernels
    except ImportError:
        return None
    return nearkernels


def _pair_hits(triangles, grid: NearGrid, o, d, tmax, k, own) -> np.ndarray:
    """(p,) bool: ray (o, d) (p, 3) float64 meets triangle k (p,) at 0 < λ < tmax (p,), k not
    `own` (p,) and its plane not through o up to float64 error -- the walk's own test
    (`NumpyBackend.occluded_leaving`) on the pairs alone."""
    a, b, c = (np.take(grid.vertices, grid.faces[k, i], axis=1).T for i in range(3))
    n = triangles.normals[k]
    height = np.abs(dot(o, n) - triangles.plane_d[k])
    bound = plane_error64(error_weight(n, np.stack([a, b, c], axis=1)) +
                          dot(np.abs(o), np.abs(n)))
    lam = ray_triangle(o, d, a, b, c)
    return (lam < tmax) & (height > bound) & (k != own)
