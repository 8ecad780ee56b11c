"""The Embree backends: one interface (`raytrace.backends`), two ways to ask Embree.

* `PacketBackend` — Embree's packet queries (`rtcIntersect8`/`rtcOccluded8`, or the width
  the CPU has) on the Embree 4 library the embreex wheel ships (`raytrace.embree4`, ctypes),
  driven by numba (`raytrace.packetkernels`, the `fast` extra): the default where both load.
* `EmbreeBackend` — embreex, one ray per call (`rtcIntersect1`/`rtcOccluded1`): the fallback
  where numba or the library is missing (said once), and the packets' cross-check
  (tests/raytrace/test_packets.py: the same answers, bit for bit).

$SHADOWVOL_EMBREE chooses: "auto" (or unset: packets where they load), "packets" (a
MissingExtra where they do not), "single" (embreex's single rays).
"""

from __future__ import annotations

import os
import threading
import warnings
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from shadowvol.checks import SceneError
from shadowvol.errors import MissingExtra, require

from .neargrid import NearGrid
from .triangles import Hits, TriangleSet

EMBREE_ENV = "SHADOWVOL_EMBREE"
EMBREE_QUERIES = ("packets", "single")


def cpu_threads() -> int:
    """How many cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


# Below this many rays the thread pool costs more than it saves.
MIN_RAYS_PER_THREAD = 4096


def _float32_bounds(dists):
    """Each ray's tfar as Embree takes it: None (unbounded), a float or (n,) float32, never
    above 1e37 (embreex's own "no bound"; float32-safe)."""
    if dists is None:
        return None
    if np.ndim(dists) == 0:
        return min(float(dists), 1e37)
    return np.minimum(np.asarray(dists, dtype=np.float32), np.float32(1e37))


class _EmbreeQueries(TriangleSet):
    """What both Embree backends share: the queries in terms of `_run` (and `first_hit`),
    the float64 test of the near pieces (`raytrace.neargrid`), the thread count."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, threads: int | None = None):
        super().__init__(vertices, faces)
        self.threads = threads or cpu_threads()
        self._near: NearGrid | None = None  # built on first use (occluded_leaving)
        self._near_lock = threading.Lock()

    def _run(self, origins, directions, dists, query: str, parallel: bool) -> np.ndarray:
        raise NotImplementedError

    def closest_triangle(self, origins, directions, tmax=None, parallel=True) -> np.ndarray:
        """Index (n,) int64 of the nearest triangle hit at 0 < t < tmax, -1 for none.
        origins, directions : (n, 3) float64 or float32 (traced in float32 either way);
        tmax : None, float or (n,)."""
        return self._run(origins, directions, tmax, "INTERSECT", parallel).astype(np.int64)

    def closest_hit(self, origins, directions, tmax=None, parallel=True) -> Hits:
        """`closest_triangle` and t, the ray–plane distance to it in the dtype of `origins`."""
        o, d = np.asarray(origins), np.asarray(directions)
        tri = self.closest_triangle(o, d, tmax, parallel)
        return Hits(self.refine(o, d, tri), tri)

    def first_hit(self, origins, directions, tmax=None) -> Hits:
        """The nearest hit at 0 < t < tmax as Embree computes it (float32, on one thread):
        t (n,) float32, Embree's own tfar (inf for none), and tri (n,) int64 (-1 for none).
        directions : (n, 3) or (1, 3)."""
        raise NotImplementedError

    def occluded(self, origins, directions, tmax=None, parallel=True) -> np.ndarray:
        """(n,) bool: does the ray hit any triangle at 0 < t < tmax (None: anywhere)?  A bounded
        Embree occlusion query: it stops at the first hit and never looks past tmax.
        directions : (n, 3), or (1, 3) for one direction shared by all rays."""
        return self._run(origins, directions, tmax, "OCCLUDED", parallel) != -1

    def occluded_leaving(self, origins, directions, tmax, own) -> np.ndarray:
        """`NumpyBackend.occluded_leaving` on the same triangles, float64: the walk's test on
        the triangles whose padded boxes the pieces' boxes touch (`raytrace.neargrid`: the
        pieces a grazing shadow ray's lift skips are short, and meet few).  The grid is built
        on the first call, once, whichever thread makes it."""
        with self._near_lock:
            if self._near is None:
                self._near = NearGrid(self.vertices, self.faces, self.fragile)
        return self._near.occluded_leaving(self, origins, directions, tmax, own)


class EmbreeBackend(_EmbreeQueries):
    """Embree (float32) through embreex, one ray per call (`rtcIntersect1`, `rtcOccluded1`):
    the single-ray path, the packets' fallback and cross-check.  Rays are split into one
    contiguous chunk per core and traced on a thread pool (embreex releases the GIL)."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, threads: int | None = None):
        super().__init__(vertices, faces, threads)
        rtcore_scene = require("embreex.rtcore_scene", "the Embree backend (or backend "
                               "'numpy', for small scenes)", package="embreex")
        TriangleMesh = require("embreex.mesh_construction", "the Embree backend",
                               package="embreex").TriangleMesh
        # float32: Embree's only vertex format.
        self._scene = rtcore_scene.EmbreeScene()
        TriangleMesh(self._scene, self.vertices.astype(np.float32),
                     self.faces.astype(np.int32))
        # embreex commits the scene (builds the BVH) lazily in the first run(); do it now, so
        # that threads never race to do it and the build is not billed to the first trace.
        self._scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32))

    def _run(self, origins, directions, dists, query: str, parallel: bool) -> np.ndarray:
        """Trace; returns primID (INTERSECT) or geomID (OCCLUDED), int32 (n,), -1 for a miss /
        an unoccluded ray.  origins (n, 3); directions (n, 3), or (1, 3): one for all rays;
        dists : None (unbounded), a float, or (n,): each ray's tfar.
        With `parallel`, in one contiguous chunk per core on a thread pool."""
        # float32: Embree's only ray format.  No copy for float32 input, strided or not:
        # embreex reads its arguments through strided buffers.
        o = np.asarray(origins, dtype=np.float32)
        d = np.asarray(directions, dtype=np.float32)
        n = len(o)
        dists = _float32_bounds(dists)
        chunks = min(self.threads, max(1, n // MIN_RAYS_PER_THREAD)) if parallel else 1
        if chunks == 1:
            return self._scene.run(o, d, dists=dists, query=query)

        def run(part: slice) -> np.ndarray:
            bound = dists if dists is None or np.ndim(dists) == 0 else dists[part]
            return self._scene.run(o[part], d if len(d) == 1 else d[part], dists=bound,
                                   query=query)

        bounds = np.linspace(0, n, chunks + 1).astype(int)
        with ThreadPoolExecutor(chunks) as pool:
            return np.concatenate(list(pool.map(run, [slice(a, b) for a, b in
                                                      zip(bounds[:-1], bounds[1:])])))

    def first_hit(self, origins, directions, tmax=None) -> Hits:
        """The nearest hit at 0 < t < tmax as Embree computes it (float32, on one thread):
        t (n,) float32, Embree's own tfar (inf for none), and tri (n,) int64 (-1 for none).
        directions : (n, 3) or (1, 3)."""
        o = np.asarray(origins, dtype=np.float32)
        d = np.asarray(directions, dtype=np.float32)
        if len(d) == 1 and len(o) > 1:
            d = np.broadcast_to(d, o.shape)
        dists = None if tmax is None else np.minimum(np.asarray(tmax, np.float32),
                                                     np.float32(1e37))
        out = self._scene.run(o, d, dists=dists, query="INTERSECT", output=1)
        tri = out["primID"].astype(np.int64)
        return Hits(np.where(tri >= 0, out["tfar"], np.float32(np.inf)), tri)


class PacketBackend(_EmbreeQueries):
    """Embree's packet queries (`raytrace.packetkernels`) on a scene of the library embreex
    ships (`raytrace.embree4`), built as embreex builds its own: the same answers as
    `EmbreeBackend`, bit for bit, in packets of the CPU's width, with the GIL released;
    `parallel` queries run on numba's threads."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, threads: int | None = None):
        super().__init__(vertices, faces, threads)
        from . import embree4, packetkernels   # (numba: an ImportError where it is missing)
        self._kernels = packetkernels
        self._lib = embree4.library()
        if self._lib is None:
            raise ImportError(embree4.why_not())
        self._scene = embree4.Scene(self._lib, self.vertices, self.faces)

    def packets(self) -> tuple:
        """(rtcIntersectN, rtcOccludedN, the scene's address, N): what numba kernels of
        their own (`raytrace.maskkernels`) need to trace on this backend's scene."""
        return self._lib.intersect, self._lib.occluded, self._scene.handle, self._lib.width

    def _trace(self, origins, directions, dists, query: int, parallel: bool):
        o = np.asarray(origins, dtype=np.float32)
        d = np.asarray(directions, dtype=np.float32)
        bounds = _float32_bounds(dists)
        tfar = np.asarray(np.float32(1e37) if bounds is None else bounds, np.float32)
        return self._kernels.trace(self._lib, self._scene.handle, query, o, d,
                                   tfar.reshape(-1), parallel)

    def _run(self, origins, directions, dists, query: str, parallel: bool) -> np.ndarray:
        """`EmbreeBackend._run` in packets: primID (INTERSECT) or 0 (OCCLUDED), -1 for none,
        (n,) int64; with `parallel`, on numba's threads."""
        kind = self._kernels.INTERSECT if query == "INTERSECT" else self._kernels.OCCLUDED
        return self._trace(origins, directions, dists, kind, parallel)[0]

    def first_hit(self, origins, directions, tmax=None) -> Hits:
        tri, t = self._trace(origins, directions, tmax, self._kernels.INTERSECT, False)
        return Hits(t, tri)


_fallback_said: list = []


def embree_queries(choice: str | None = None) -> str:
    """Which Embree queries the "embree" backend runs: "packets" or "single".  choice None:
    $SHADOWVOL_EMBREE, where unset or "auto" packets when numba and the library load, else
    single rays (said once per process).  An unknown name is a SceneError naming where it
    came from; packets asked for but missing, a MissingExtra (exit status 2 in the CLI)."""
    where = "embree queries"
    if choice is None:
        choice = os.environ.get(EMBREE_ENV, "auto").strip().lower() or "auto"
        where = EMBREE_ENV
    if choice not in EMBREE_QUERIES + ("auto",):
        raise SceneError(where, f"unknown Embree queries {choice!r} (one of: auto, "
                                f"{', '.join(EMBREE_QUERIES)})")
    if choice == "single":
        return "single"
    why = _packets_missing()
    if not why:
        return "packets"
    if choice == "packets":
        raise MissingExtra(f"{where}=packets (Embree's packet queries: {why})", "numba", "fast")
    from . import embree4
    # no embreex at all: the single rays' own error (MissingExtra) says so, alone
    if not _fallback_said and embree4.embreex_module() is not None:
        _fallback_said.append(why)
        warnings.warn(f"Embree's packet queries unavailable ({why}): tracing single rays "
                      f"(embreex)", RuntimeWarning, stacklevel=2)
    return "single"


def _packets_missing() -> str:
    """Why the packets cannot run here ("" when they can)."""
    try:
        from . import packetkernels  # noqa: F401
    except ImportError as exc:
        return f"numba: {exc}"
    from . import embree4
    return "" if embree4.library() is not None else embree4.why_not()


def embree_backend(vertices: np.ndarray, faces: np.ndarray) -> _EmbreeQueries:
    """The "embree" backend of `embree_queries()`'s choice for the triangles."""
    if embree_queries() == "packets":
        return PacketBackend(vertices, faces)
    return EmbreeBackend(vertices, faces)
