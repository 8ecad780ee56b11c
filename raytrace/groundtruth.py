"""Ground truth for vision datasets from the reference ray tracer (docs/CONVENTIONS.md, "Ground
truth"): per pixel the depth, the distance, the face normal and the object id of the visible
point, and per light how many samples face it, how many reach it and which objects block it.

Everything rides the masks' own rays (`raytrace.masks`): the same visible triangle, the same
float64 hit point, the same shadow segments with the same margins and the same float64 pieces
that a long lift skips (`raytrace.masks._NearPieces`).  An area light is its N samples
(`shadowvol.scene.hard_lights`), each traced as a hard light; its counts add up and its
casters OR, so `lit_count` equals `raytrace.soft_masks`' and `lit` `shadow_masks`'.  `casters`
traces each segment the scene found blocked again against each object alone whose padded box
it meets (one backend per object, in the masks' frame, the visible triangle excluded by id in
its own object), but for the last such object where every other found it clear (then the
blocker can only be there; `_candidates`): bit j mod 64 of word j div 64 of `casters[i, p]`
says "object j blocks p's segment to some facing sample of light i".  `object_id` counts up
to 65535 objects (uint16); `casters` any number.
"""

from __future__ import annotations

import dataclasses
import weakref

import numpy as np

from shadowvol import frame
from shadowvol.cameras import calibration
from shadowvol.frame import GROUND_TRUTH, Frame, check_outputs
from shadowvol.scene import Scene, hard_lights

from .backends import PacketBackend, TriangleBackend, for_each_tile, make_backend
from .camera import RayGrid
from .masks import (
    MASK_TILE_RAYS,
    MaskTracer,
    _blocked,
    _local_light,
    _near_blocked,
    _primary_hits,
    _segments,
    scene_backend,
)
from .switches import backend_kind, receiving

# An object's box is widened by this much of its largest coordinate (eye's frame) before a
# segment is culled against it: float32 rounding of the corners (2**-24) and of the segment's
# start and direction, 100 times over.  A speed-up only: the culled segments are those that
# the object's own backend would find unblocked.
BOX_PAD_RELATIVE = 1e-5
# Tuning (memory only, never results): the most (object, segment) candidates `casters` lists
# at once (int64 indices: 32 MiB), the blocked segments taken in parts of at most this over
# the number of objects.
CANDIDATE_PAIRS = 1 << 22


@dataclasses.dataclass(frozen=True, eq=False, kw_only=True)
class GroundTruth(Frame):
    """One frame's masks, the ground-truth outputs asked for (None otherwise) and the camera
    (`shadowvol.frame.Frame`); the ray tracer adds nothing to it, and always gives `lit`,
    `coverage`, `lit_count`, `samples` and `calibration`.

    depth : (H, W) float32, eye-space depth (along the view axis); inf where nothing is hit
    distance : (H, W) float32, from the eye along the pixel's ray; inf where nothing is hit
    normal : (H, W, 3) float32, the world-space unit face normal, turned toward the camera;
        0 where nothing is hit
    object_id : (H, W) uint16, 0 = background, k = scene.objects[k - 1]
    facing : (L, H, W) bool, facing_count > 0
    facing_count : (L, H, W) uint16, how many samples face the pixel: n·l > 0 and inside the
        sample's cone (a spot light's; a rect or disk sample's 90 degrees)
    casters : (L, H, W, K) uint64, K = max(1, ceil(n_objects / 64)): bit j mod 64 of word
        j div 64 set when scene.objects[j] blocks the segment to some facing sample
    """


class _ObjectTracers:
    """One backend per object, in the masks' frame: what `casters` traces segments against.

    first : (n + 1,) int64, object j's triangles are first[j] .. first[j + 1] − 1 of the
    scene's; object : (M,) int64, each scene triangle's object; lo, hi : (n, 3) float64, each
    object's bounding box, padded by BOX_PAD_RELATIVE of its largest coordinate (a segment
    that misses the padded box cannot meet the object in float32 either)."""

    def __init__(self, scene: Scene, mask_tracer: MaskTracer):
        self.local = [o.vertices - mask_tracer.origin for o in scene.objects]
        self.faces = [o.faces.copy() for o in scene.objects]
        self.casts = [o.cast_shadows for o in scene.objects]
        self.built = False
        self.normals: np.ndarray | None = None   # `face_normals` of the scene, when asked

    def built_for(self, scene: Scene, mask_tracer: MaskTracer) -> "_ObjectTracers":
        """These, with their backends built (on the first call)."""
        if not self.built:
            self._build(scene, mask_tracer)
            self.built = True
        return self

    def world_normals(self, corners) -> np.ndarray:
        """`face_normals(corners())`, the scene's world-space corners, computed once."""
        if self.normals is None:
            self.normals = face_normals(corners())
        return self.normals

    def fits(self, scene: Scene, origin: np.ndarray) -> bool:
        """Whether these tracers are still `scene`'s in the frame of `origin`: the same objects,
        vertices, faces and switches, compared by value (a scene edited in place is rebuilt)."""
        return len(scene.objects) == len(self.local) and all(
            o.cast_shadows == c and np.array_equal(o.faces, f)
            and np.array_equal(o.vertices - origin, v)
            for o, c, f, v in zip(scene.objects, self.casts, self.faces, self.local))

    def _build(self, scene: Scene, mask_tracer: MaskTracer) -> None:
        kind = backend_kind(mask_tracer.tracer)
        _, _, ids = scene.triangles()
        self.object = ids.astype(np.int64)
        self.first = np.searchsorted(self.object, np.arange(len(scene.objects) + 1))
        # each object's own vertices and faces (its face k is scene triangle first[j] + k);
        # None for an object that casts no shadow (`Object.cast_shadows`): it blocks nothing
        local = self.local
        self.tracers: list[TriangleBackend | None] = [
            make_backend(kind, v, o.faces) if o.cast_shadows else None
            for v, o in zip(local, scene.objects)]
        lo = np.array([v[o.faces.reshape(-1)].min(axis=0) for v, o in zip(local, scene.objects)])
        hi = np.array([v[o.faces.reshape(-1)].max(axis=0) for v, o in zip(local, scene.objects)])
        pad = BOX_PAD_RELATIVE * np.maximum(np.abs(lo), np.abs(hi)).max(axis=1, keepdims=True)
        self.lo, self.hi = lo - pad - np.finfo(np.float32).tiny, hi + pad + np.finfo(
            np.float32).tiny


# each MaskTracer's backend -> its scene's per-object tracers and world normals, built on the first
# call that asks, kept while the backend lives (a turntable over one MaskTracer builds them once)
_OBJECT_TRACERS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def _object_tracers(scene: Scene, mt: MaskTracer) -> _ObjectTracers:
    """`scene`'s per-object tracers in the frame of `mt`, reused when `mt` made them before."""
    kept = _OBJECT_TRACERS.get(mt.tracer)
    if kept is None or not kept.fits(scene, mt.origin):
        kept = _OBJECT_TRACERS[mt.tracer] = _ObjectTracers(scene, mt)
    return kept


def ground_truth(scene: Scene, outputs=GROUND_TRUTH, backend: str | MaskTracer = "embree"
                 ) -> GroundTruth:
    """The masks of `scene` with the ground-truth `outputs` (names from
    `shadowvol.frame.GROUND_TRUTH`; default all), the counts and the calibration.

    backend : "embree", "numpy", or `raytrace.masks.scene_backend(scene, ...)` built once.
    `lit` and `coverage` equal `shadow_masks(scene, backend)`; `casters.any(-1)` equals
    `lit_count < facing_count`.  Tiled and threaded as `shadow_masks` is."""
    outputs = check_outputs(outputs, GROUND_TRUTH, objects=len(scene.objects))
    mt = scene_backend(scene, backend) if isinstance(backend, str) else backend
    tracer, triangles, origin = mt
    H, W, L, n = scene.height, scene.width, len(scene.lights), len(scene.objects)
    kept = _object_tracers(scene, mt) if {"casters", "normal"} & set(outputs) else None
    objects = kept.built_for(scene, mt) if "casters" in outputs else None
    coverage = np.zeros(H * W, bool)
    # the outputs asked for, flat (pixels row-major), with what is stored where nothing is hit
    out = {name: frame.blank(name, frame.shape(name, L, H, W, flat=True, objects=n))
           for name in outputs}
    counts = {name: np.zeros((L, H * W), np.uint16) for name in ("lit_count", "facing_count")}
    vertices, faces, ids = scene.triangles()
    # the output normals: world-space (b − a) × (c − a), normalised in float64 (CONVENTIONS),
    # not the frame's (the same up to rounding, and the same sign: `hit.side` turns either)
    world_normals = kept.world_normals(lambda: vertices[faces]) if "normal" in out else None
    camera = scene.camera.translated(-origin)
    grids = (RayGrid(camera, W, H, np.float32), RayGrid(camera, W, H, np.float64))
    # every sample of every light, as the light it counts for and a hard light
    lights = [(i, _local_light(sample, origin, triangles))
              for i, light in enumerate(scene.lights) for sample in hard_lights(light)]
    rows_per_tile = max(1, MASK_TILE_RAYS // W)
    tiles = [slice(y, min(y + rows_per_tile, H)) for y in range(0, H, rows_per_tile)]

    def trace_tile(rows: slice) -> None:
        covered, index, hit = _primary_hits(tracer, triangles, grids, rows)
        first = rows.start * W
        coverage[first:first + covered.size] = covered
        if hit is None:
            return
        pixel = first + index
        _pixel_outputs(out, grids[1], rows, first, index, hit, world_normals, ids)
        for i, light in lights:
            _shadow_tile(tracer, objects, light, hit, scene.extent, pixel, counts, i,
                         out.get("casters"))

    for_each_tile(trace_tile, tiles, tracer)
    samples = np.array([len(hard_lights(light)) for light in scene.lights], np.int64)
    lit = counts["lit_count"] == samples[:, None]
    if "facing" in out:
        out["facing"] = counts["facing_count"] > 0
    if "facing_count" in out:
        out["facing_count"] = counts["facing_count"]
    return GroundTruth(lit=lit.reshape(L, H, W), coverage=coverage.reshape(H, W),
                       calibration=calibration(scene),
                       lit_count=counts["lit_count"].reshape(L, H, W), samples=samples,
                       **{name: value.reshape(frame.shape(name, L, H, W, objects=n))
                          for name, value in out.items()})


PIXEL_OUTPUTS = ("depth", "distance", "normal", "object_id")


def _pixel_outputs(out: dict, grid64: RayGrid, rows: slice, first: int, index: np.ndarray,
                   hit, world_normals: np.ndarray | None, ids: np.ndarray) -> None:
    """The per-pixel outputs in `out` (flat, pixels row-major) of a tile's hits at pixels
    first + index (h,): depth, distance (depth · |v|, v the pixel's float64 direction of
    depth 1), normal (world_normals of the hit triangle turned toward the camera) and
    object_id.  In one numba pass where it loads (`maskkernels.pixel_outputs`: the same
    bits), else in numpy."""
    try:
        from .maskkernels import pixel_outputs
    except ImportError:
        pixel_outputs = None
    if pixel_outputs is not None:
        empty = {name: np.zeros((0, 3) if name == "normal" else 0, frame.FIELDS[name].dtype)
                 for name in PIXEL_OUTPUTS}
        want = np.array([name in out for name in PIXEL_OUTPUTS])
        normals = world_normals if world_normals is not None else np.zeros((0, 3))
        pixel_outputs(first, grid64.width, rows.start, index, grid64.row, grid64.col,
                      hit.depth, hit.tri, hit.side, normals, ids, want,
                      *[out.get(name, empty[name]) for name in PIXEL_OUTPUTS])
        return
    pixel = first + index
    if "depth" in out:
        out["depth"][pixel] = hit.depth
    if "distance" in out:
        view = np.take(grid64.directions(rows), index, axis=1)
        out["distance"][pixel] = hit.depth * np.sqrt((view * view).sum(axis=0))
    if "normal" in out:
        out["normal"][pixel] = world_normals[hit.tri] * hit.side[:, None]
    if "object_id" in out:
        out["object_id"][pixel] = ids[hit.tri] + 1


def _shadow_tile(tracer, objects: _ObjectTracers | None, light, hit, reach: float,
                 pixel: np.ndarray, counts: dict[str, np.ndarray], i: int,
                 casters: np.ndarray | None) -> None:
    """One hard light (a sample of light i) over a tile's hits at `pixel` (h,) int64: its
    facing and lit pixels added to `counts` (L, H * W) uint16 each, its blockers ORed into
    `casters` (L, H * W, K) uint64 when given.  Lit as `masks._lit` decides it: the segment
    past the lift unblocked, and then the float64 near piece a long lift skips
    (`masks._NearPieces`) unblocked too."""
    seg = receiving(tracer, light.light,
                    _segments(light, hit, reach, isinstance(tracer, PacketBackend)), hit)
    own, fragile = hit.tri[seg.rays], hit.fragile[seg.rays]
    start = seg.start.copy() if casters is not None else seg.start
    tmax = None if seg.tmax is None else seg.tmax.copy()
    blocked = _blocked(tracer, seg.start, seg.direction, seg.tmax, own, fragile)
    lit_here = seg.facing.copy()
    lit_here[seg.rays] = ~blocked
    left_lit = lit_here[seg.near.rays]  # the near pieces whose rest left them lit
    if casters is None:
        near = seg.near.where(left_lit)
        lit_here[near.rays] = ~_near_blocked(tracer, near, hit.tri[near.rays])
    else:   # every near piece asked of the scene: the objects are asked of those blocked only
        near_blocked = _near_blocked(tracer, seg.near, hit.tri[seg.near.rays])
        lit_here[seg.near.rays[left_lit]] = ~near_blocked[left_lit]
    counts["lit_count"][i, pixel] += lit_here
    counts["facing_count"][i, pixel] += seg.facing
    if casters is not None and blocked.any():
        b = np.flatnonzero(blocked)
        casters[i, pixel[seg.rays[b]]] |= _caster_bits(
            objects, start[:, b], seg.direction if seg.direction.shape[1] == 1
            else seg.direction[:, b], None if tmax is None else tmax[b], own[b], fragile[b])
    if casters is not None and near_blocked.any():
        near = seg.near.where(near_blocked)
        casters[i, pixel[near.rays]] |= _near_caster_bits(objects, near, hit.tri[near.rays])


def face_normals(corners: np.ndarray) -> np.ndarray:
    """(M, 3) float64 unit normals (b − a) × (c − a) of world-space corners (M, 3, 3) (zero
    for a degenerate triangle)."""
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def _caster_bits(objects: _ObjectTracers, start: np.ndarray, direction: np.ndarray,
                 tmax: np.ndarray | None, own: np.ndarray, fragile: np.ndarray) -> np.ndarray:
    """(b, K) uint64: the objects that block each of b segments that the scene's backend found
    blocked, as bits (object j: bit j mod 64 of word j div 64).

    start (3, b) float32, direction (3, b) or (3, 1) float32, tmax (b,) float32 or None: the
    segments as `_segments` made them (before `_blocked` moved any start); own (b,) int64 the
    scene triangle each leaves, fragile (b,) bool.  Each object's backend is asked the masks'
    own question (`_blocked`), its own triangle excluded by id in the object it belongs to,
    except where the answer is known (`_candidates`): a segment that does not leave a sliver,
    blocked in the scene and found clear by every other object it may meet, is blocked by the
    last one."""
    start64 = start.astype(np.float64)
    direction64 = np.broadcast_to(direction, start.shape).astype(np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse = 1.0 / direction64
    end = np.inf if tmax is None else tmax.astype(np.float64)

    def ask(j, tracer, k, local_own, mine):
        return _blocked(tracer, start[:, k], direction if direction.shape[1] == 1
                        else direction[:, k], None if tmax is None else tmax[k].copy(),
                        local_own, fragile[k] & mine)

    return _candidates(objects, start64, inverse, end, own, ~fragile, ask)


def _near_caster_bits(objects: _ObjectTracers, near, own: np.ndarray) -> np.ndarray:
    """(q, K) uint64: the objects that block the float64 near pieces `near`
    (`masks._NearPieces`), which the scene's backend found blocked, of segments leaving scene
    triangles own (q,), as bits (object j: bit j mod 64 of word j div 64).  Each object's
    backend is asked the masks' own question (`masks._near_blocked`), its own triangle
    excluded by id in the object it belongs to, except where the answer is known
    (`_candidates`)."""
    direction = np.broadcast_to(near.direction, near.origin.shape)
    with np.errstate(divide="ignore"):
        inverse = 1.0 / direction

    def ask(j, tracer, k, local_own, mine):
        keep = np.zeros(len(own), bool)
        keep[k] = True
        return _near_blocked(tracer, near.where(keep), local_own)

    return _candidates(objects, near.origin, inverse, near.tmax, own,
                       np.ones(len(own), bool), ask)


def _candidates(objects: _ObjectTracers, start: np.ndarray, inverse: np.ndarray, end,
                own: np.ndarray, deducible: np.ndarray, ask) -> np.ndarray:
    """(b, K) uint64: the casting objects that block each of b segments the scene found
    blocked, as bits.  An object may block a segment only where the segment meets its padded
    box or leaves one of its triangles (own (b,) int64): its candidates.  ask(j, tracer, k,
    local_own, mine) -> (len(k),) bool asks object j of the segments k (ascending), own
    triangle local_own (-1: not in j; mine: in j).

    The objects are asked in order; where a segment is `deducible` (b,) bool and every
    candidate before its last found it clear, the last is not asked: it blocks.  The scene's
    answer is its triangles' (an occlusion query without exclusions but the own triangle's,
    the same in the object's backend: `_blocked` retries slivers only, which are not
    deducible; `occluded_leaving` excludes per triangle), and the triangles of the other
    objects cannot meet the segment, so the blocker is in the last one."""
    bits = np.zeros((len(own), frame.caster_words(len(objects.tracers))), np.uint64)
    # at most CANDIDATE_PAIRS (object, segment) candidates listed at once
    step = max(1, CANDIDATE_PAIRS // max(1, len(objects.tracers)))
    for s in range(0, len(own), step):
        part = slice(s, min(s + step, len(own)))
        _ask_candidates(objects, start[:, part], inverse[:, part],
                        end if np.ndim(end) == 0 else end[part], own[part], deducible[part],
                        lambda j, tracer, k, *rest: ask(j, tracer, k + part.start, *rest),
                        bits[part])
    return bits


def _ask_candidates(objects: _ObjectTracers, start, inverse, end, own, deducible, ask,
                    bits) -> None:
    """`_candidates` of some segments, their bits ORed into bits (b, K) (a view)."""
    own_object = objects.object[own]
    asked = []   # (j, tracer, k, mine[k]) per casting object with candidates
    last = np.full(len(own), -1, np.int64)
    for j, k in _boxes_met(objects, start, inverse, end, own_object):
        asked.append((j, objects.tracers[j], k, own_object[k] == j))
        last[k] = j
    found = ~deducible   # a segment not deducible counts as found: every candidate is asked
    for j, tracer, k, mine in asked:
        known = (last[k] == j) & ~found[k]
        hit = known.copy()
        q = np.flatnonzero(~known)
        if len(q):
            hit[q] = ask(j, tracer, k[q], np.where(mine[q], own[k[q]] - objects.first[j], -1),
                         mine[q])
        found[k[hit]] = True
        bits[k[hit], j // frame.CASTER_WORD_BITS] |= np.uint64(1) << np.uint64(
            j % frame.CASTER_WORD_BITS)


def _boxes_met(objects: _ObjectTracers, start: np.ndarray, inverse: np.ndarray, end,
               own_object: np.ndarray):
    """(j, k) for each casting object j, in order, that some segment may meet: k ascending,
    the segments that meet j's padded box (`_meets_box`) or leave it (own_object == j).  In
    numba where it loads (`maskkernels.box_candidates`, the same segments), else in numpy."""
    try:
        from .maskkernels import box_candidates
    except ImportError:
        box_candidates = None
    casts = np.array([t is not None for t in objects.tracers], bool)
    if box_candidates is not None:
        first, k = box_candidates(
            np.ascontiguousarray(start, np.float64), np.ascontiguousarray(inverse, np.float64),
            np.broadcast_to(np.asarray(end, np.float64), own_object.shape).copy(),
            objects.lo, objects.hi, casts, own_object)
        return [(j, k[first[j]:first[j + 1]]) for j in np.flatnonzero(first[1:] > first[:-1])]
    out = []
    for j in np.flatnonzero(casts):
        k = np.flatnonzero(_meets_box(start, inverse, end, objects.lo[j], objects.hi[j])
                           | (own_object == j))
        if len(k):
            out.append((j, k))
    return out


def _meets_box(start: np.ndarray, inverse: np.ndarray, end, lo: np.ndarray, hi: np.ndarray
               ) -> np.ndarray:
    """(b,) bool: does the segment start + t·d, 0 <= t <= end, meet the box [lo, hi]?  start,
    inverse (1/d, inf for a zero component) : (3, b) float64; end : (b,) or inf."""
    with np.errstate(invalid="ignore"):  # 0 · inf: a zero component inside the slab
        t1 = (lo[:, None] - start) * inverse
        t2 = (hi[:, None] - start) * inverse
    lower = np.fmin(t1, t2)
    upper = np.fmax(t1, t2)
    # nan (0 · inf) means the ray runs inside that slab: fmax/fmin drop it
    t_in = np.fmax(np.fmax(lower[0], lower[1]), np.fmax(lower[2], 0.0))
    t_out = np.fmin(np.fmin(upper[0], upper[1]), np.fmin(upper[2], end))
    return t_in <= t_out
