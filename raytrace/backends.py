"""Triangle backends: one interface, two implementations.

* `NumpyBackend` — the reference: the course's ray–triangle test (`intersect.ray_triangle`) in
  float64 over a simple BVH, traversed a whole set of rays at a time (each node passes on the
  subset of rays that hit its box).  Fine for small scenes and tests.
* `EmbreeBackend` — Intel Embree through `embreex`: the production path, for large meshes.

Both give the same answers (tests/raytrace/test_backends.py) up to float32 rounding at triangle
edges:

    closest_hit(origins, directions, tmax=None) -> Hits(t, tri)
    occluded(origins, directions, tmax=None)    -> (n,) bool

`t` is always computed by the ray–plane formula against the plane of the hit triangle, in the
precision of the rays given (float64 rays: float64-accurate hit points, whichever backend chose
the triangle; float32 rays, as the masks use: float32).

Embree and float32: Embree converts vertices, origins, directions and distances to float32.  The
choice of triangle can therefore differ from float64 for rays within ~1e-7 (relative) of an edge,
and a ray leaving a surface must keep clear of it by more than float32 can resolve: the masks
shorten each shadow segment at its ends (`tolerances.shadow_height`, `tolerances.light_margin`,
and the reasoning in `raytrace.tolerances`); Whitted's secondary rays start
`tolerances.SURFACE_OFFSET_RELATIVE` off the surface.  embreex releases the GIL while it traces,
so the rays are split into one chunk per core, traced on a thread pool.  Shadow rays are *bounded* occlusion
queries (Embree stops at the first hit before tfar), which trimesh's wrapper does not offer.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from typing import NamedTuple

import numpy as np

from .embree import MIN_RAYS_PER_THREAD, EmbreeBackend, PacketBackend, cpu_threads, embree_backend
from .intersect import ray_triangle
from .tolerances import BVH_BOX_PAD_RELATIVE, plane_error64
from .triangles import Hits, TriangleBackend, TriangleSet

# the names the rest of raytrace/ imports from here
__all__ = ["BACKENDS", "EmbreeBackend", "Hits", "MIN_RAYS_PER_THREAD", "NumpyBackend",
           "PacketBackend", "TriangleBackend", "TriangleSet", "cpu_threads", "for_each_tile",
           "make_backend"]

BACKENDS = ("numpy", "embree")

# Tuning of the numpy backend (not tolerances: they change speed, never results): triangles per
# BVH leaf, and the most (ray, triangle) pairs tested at once (bounds the temporaries, ~30
# float64 values per pair).
BVH_LEAF_SIZE = 32
MAX_PAIRS_PER_BATCH = 1 << 18


def make_backend(name: str, vertices: np.ndarray, faces: np.ndarray) -> TriangleBackend:
    """A backend by name ("numpy" or "embree") for the triangles (vertices, faces); "embree"
    is Embree's packets or its single rays, as `raytrace.embree.embree_backend` chooses."""
    if name == "numpy":
        return NumpyBackend(vertices, faces)
    if name == "embree":
        return embree_backend(vertices, faces)
    raise ValueError(f"unknown backend {name!r} (one of: {', '.join(BACKENDS)})")


def _tmax_array(tmax, n: int) -> np.ndarray:
    if tmax is None:
        return np.full(n, np.inf)
    return np.broadcast_to(np.asarray(tmax, dtype=np.float64), (n,)).copy()


# ---------------------------------------------------------------------------------------------
# numpy reference
# ---------------------------------------------------------------------------------------------

class _Node(NamedTuple):
    lo: np.ndarray  # (3,) box corner
    hi: np.ndarray
    children: tuple  # (left, right) node indices, or () for a leaf
    tris: np.ndarray  # triangle indices of a leaf


class NumpyBackend(TriangleSet):
    """The reference backend: float64, the course's ray–triangle test, over a median-split BVH.

    Traversal is by sets of rays: a node receives the indices of the rays that may hit it, keeps
    those whose box entry lies before their current nearest hit, and hands them on to its
    children; a leaf tests all its rays against all its triangles at once.  No per-ray loop.
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, leaf_size: int = BVH_LEAF_SIZE):
        super().__init__(vertices, faces)
        tri = self.vertices[self.faces]
        self._a, self._b, self._c = tri[:, 0], tri[:, 1], tri[:, 2]
        pad = BVH_BOX_PAD_RELATIVE * float(np.abs(tri).max())
        lo_t, hi_t = tri.min(axis=1) - pad, tri.max(axis=1) + pad
        centroids = tri.mean(axis=1)
        self.nodes: list[_Node] = []
        # Iterative build, depth first: each stack entry is (triangle indices, parent node id).
        # The left half is pushed last, so it is built (and listed as a child) first.
        stack = [(np.arange(len(tri)), None)]
        pending_children: dict[int, list[int]] = {}
        while stack:
            idx, parent = stack.pop()
            node_id = len(self.nodes)
            lo, hi = lo_t[idx].min(axis=0), hi_t[idx].max(axis=0)
            if len(idx) <= leaf_size:
                self.nodes.append(_Node(lo, hi, (), idx))
            else:
                c = centroids[idx]
                axis = int(np.argmax(c.max(axis=0) - c.min(axis=0)))
                order = idx[np.argsort(c[:, axis], kind="stable")]
                half = len(order) // 2
                self.nodes.append(_Node(lo, hi, (), idx[:0]))
                pending_children[node_id] = []
                stack.append((order[half:], node_id))
                stack.append((order[:half], node_id))
            if parent is not None:
                pending_children[parent].append(node_id)
        for node_id, kids in pending_children.items():
            n = self.nodes[node_id]
            self.nodes[node_id] = n._replace(children=tuple(kids))

    def _box_entry(self, node: _Node, o: np.ndarray, inv: np.ndarray) -> np.ndarray:
        """Slab test: t where rays (o, 1/d) enter the node's box, clipped to >= 0; inf if never."""
        t1 = (node.lo - o) * inv
        t2 = (node.hi - o) * inv
        t_in = np.maximum(np.minimum(t1, t2).max(axis=1), 0.0)
        t_out = np.maximum(t1, t2).min(axis=1)
        return np.where(t_in <= t_out, t_in, np.inf)

    def _traverse(self, origins, directions, t_best, tri_best, any_hit: bool,
                  exclude=None) -> None:
        """Fill t_best/tri_best (n,) in place; with any_hit, a ray stops at its first hit
        (t_best becomes -inf so that every box culls it).  exclude(rays, tris) -> (r, m) bool:
        the (ray, triangle) pairs that do not count."""
        # A zero direction component becomes the smallest normal float, so that 1/d is huge but
        # finite and the slab test never computes 0 * inf = NaN.
        d = np.where(directions == 0.0, np.finfo(np.float64).tiny, directions)
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
            inv = 1.0 / d
        stack = [(0, np.flatnonzero(t_best > 0.0))]
        while stack:
            node_id, idx = stack.pop()
            node = self.nodes[node_id]
            with np.errstate(over="ignore", invalid="ignore"):
                entry = self._box_entry(node, origins[idx], inv[idx])
            idx = idx[entry < t_best[idx]]
            if len(idx) == 0:
                continue
            if node.children:
                stack.extend((kid, idx) for kid in node.children)
                continue
            tris = node.tris
            step = max(1, MAX_PAIRS_PER_BATCH // len(tris))
            for s in range(0, len(idx), step):
                rays = idx[s:s + step]
                lam = ray_triangle(origins[rays, None], directions[rays, None],
                                   self._a[None, tris], self._b[None, tris], self._c[None, tris])
                if exclude is not None:
                    lam = np.where(exclude(rays, tris), np.inf, lam)
                j = np.argmin(lam, axis=1)
                t = lam[np.arange(len(rays)), j]
                better = t < t_best[rays]
                if any_hit:
                    t_best[rays[better]] = -np.inf
                else:
                    t_best[rays[better]] = t[better]
                tri_best[rays[better]] = tris[j[better]]

    def closest_triangle(self, origins, directions, tmax=None, parallel=True) -> np.ndarray:
        """Index (n,) int64 of the nearest triangle hit at 0 < t < tmax, -1 for none.
        origins, directions : (n, 3) float64 (or float32: traced in float64 all the same);
        tmax : None, float or (n,).  `parallel` is ignored (numpy runs on one core)."""
        o = np.asarray(origins, dtype=np.float64)
        d = np.asarray(directions, dtype=np.float64)
        t_best = _tmax_array(tmax, len(o))
        tri_best = np.full(len(o), -1, np.int64)
        self._traverse(o, d, t_best, tri_best, any_hit=False)
        return tri_best

    def closest_hit(self, origins, directions, tmax=None, parallel=True) -> Hits:
        """`closest_triangle` and t, the ray–plane distance to it in the dtype of `origins`."""
        o, d = np.asarray(origins), np.asarray(directions)
        tri = self.closest_triangle(o, d, tmax)
        return Hits(self.refine(o, d, tri), tri)

    def first_hit(self, origins, directions, tmax=None) -> Hits:
        """The nearest hit at 0 < t < tmax as this backend computes it: t (n,) float64 (its
        own λ, inf for none) and tri (n,) int64 (-1 for none).  directions : (n, 3) or (1, 3)."""
        o = np.asarray(origins, dtype=np.float64)
        d = np.broadcast_to(np.asarray(directions, dtype=np.float64), o.shape)
        t_best = _tmax_array(tmax, len(o))
        tri_best = np.full(len(o), -1, np.int64)
        self._traverse(o, d, t_best, tri_best, any_hit=False)
        return Hits(np.where(tri_best >= 0, t_best, np.inf), tri_best)

    def occluded(self, origins, directions, tmax=None, parallel=True) -> np.ndarray:
        """(n,) bool: does the ray hit any triangle at 0 < t < tmax (None: anywhere)?
        directions : (n, 3), or (1, 3) for one direction shared by all rays."""
        o = np.asarray(origins, dtype=np.float64)
        d = np.broadcast_to(np.asarray(directions, dtype=np.float64), o.shape)
        t_best = _tmax_array(tmax, len(o))
        tri_best = np.full(len(o), -1, np.int64)
        self._traverse(o, d, t_best, tri_best, any_hit=True)
        return tri_best >= 0


    def occluded_leaving(self, origins, directions, tmax, own) -> np.ndarray:
        """(n,) bool: does the ray leaving a surface at its origin hit, at 0 < t < tmax, a
        triangle other than own (n,) int64 (the one it leaves) and other than those whose
        plane passes through the origin up to its float64 error (`tolerances.plane_error64`:
        they meet the ray's line there only, so every hit on them is rounding)?  Float64
        throughout.  origins (n, 3) float64; directions (n, 3) or (1, 3); tmax (n,)."""
        o = np.asarray(origins, dtype=np.float64)
        d = np.broadcast_to(np.asarray(directions, dtype=np.float64), o.shape)
        own = np.asarray(own, dtype=np.int64)
        weight = self.weight

        def exclude(rays, tris):
            n = self.normals[tris]
            height = np.abs(o[rays] @ n.T - self.plane_d[tris])
            bound = plane_error64(weight[tris] + np.abs(o[rays]) @ np.abs(n).T)
            return (height <= bound) | (tris[None, :] == own[rays, None])

        t_best = _tmax_array(tmax, len(o))
        tri_best = np.full(len(o), -1, np.int64)
        self._traverse(o, d, t_best, tri_best, any_hit=True, exclude=exclude)
        return tri_best >= 0


def for_each_tile(work, tiles: list, tracer) -> None:
    """work(tile) for every tile, on a pool of the tracer's `threads` (at most one per tile;
    Embree and numpy's large operations release the GIL); a tile's exception is raised here."""
    threads = min(getattr(tracer, "threads", 1), len(tiles))
    if threads <= 1:
        for tile in tiles:
            work(tile)
    else:
        with ThreadPoolExecutor(threads) as pool:
            list(pool.map(work, tiles))  # list(): re-raises a tile's exception here
