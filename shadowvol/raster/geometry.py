"""The scene's geometry on the GPU, uploaded once per scene.

All objects become one triangle soup (three vertices per triangle, objects one after another).
The geometry pass draws its positions in one draw and keys each pixel by the triangle's index
(gl_VertexID / 3), the key of the per-triangle storage buffer (face normal, first corner, object
index) that the deferred shading pass reads; the z-fail near caps draw subsets of the same
vertices in the same order, so their depths equal the geometry pass's bit for bit.  (Why not an
indexed mesh keyed by gl_PrimitiveID: benchmarks/OPTIMISATIONS.md.)
The soup's other per-vertex attributes (normal, first corner, object: the GPU caps and the
planar shadows' forward passes) are built on first use, one buffer each.

float32 is used on the GPU because that is what GL rasterizes; normals and corners are computed
in float64 and rounded once, positions in the float32 frame of the eye (`projection.to_frame`:
float64 world minus `origin`, the ray tracer's frame too).  When a frame's eye moves, `move_to`
rewrites the buffers that hold positions (the soup's positions and first corners, the
per-triangle data) in place, from the scene's float64 vertices; normals, objects and topology
stay.  No host copy of what was uploaded is kept (on a software GL, llvmpipe, a buffer is host
memory already): the buffers are written CHUNK triangles at a time, and `frame_corners`
recomputes any triangles' float32 corners, bit for bit as uploaded, when they are needed.
Edge topology (CPU, float64, world space) is computed here too, once per object.

Huge triangles (`guard`): per frame, `set_view` cuts the triangles that reach far outside the
view to its guard band, in float64.  The pieces go after the soup's M triangles, in every soup
buffer (keys M.., each carrying its triangle's normal, first corner and object), and the
triangles they replace ("holes") are skipped by the draws that use `spans` (the geometry pass,
the near caps); the soup's own M triangles are never changed, so the forward passes (planar
shadows) draw them as they are.
"""

from __future__ import annotations

from dataclasses import dataclass

import moderngl
import numpy as np

from shadowvol.cameras import frame_origin
from shadowvol.errors import RenderError
from shadowvol.raster import guard
from shadowvol.raster.projection import to_frame
from shadowvol.raster.textures import SceneTextures, texture_index
from shadowvol.raster.volumes.topology import Topology
from shadowvol.scene import Scene, SceneError

MAX_TRIANGLES = 2 ** 24  # the G-buffer's surface key is a float32 integer (target.py)


@dataclass(frozen=True)
class ObjectRange:
    """Where object `index` lives in the soup: triangles [first, first + count)."""

    index: int
    first: int
    count: int


# the soup's attributes that hold positions, rewritten when the frame moves (and the
# per-triangle data, which holds the first corner)
_FRAMED = ("in_position", "in_corner", "triangle_data")
# bytes per triangle of each soup buffer (three vertices each, but the per-triangle data)
_BYTES = {"in_position": 36, "in_corner": 36, "in_normal": 36, "in_object": 12,
          "triangle_data": 32, "in_uv": 24, "in_colour": 36}
# the soup's per-vertex surface attributes (textures and vertex colours), interpolated by the
# geometry pass into the G-buffer: each object's own, (n, C) per vertex, C of each
_SURFACE = {"in_uv": 2, "in_colour": 3}
# triangles built at a time when a soup buffer is written: no array of the whole soup but the
# per-triangle normals and objects is made on the host (on a software GL a buffer is host
# memory too, so a kept copy would be a second one)
CHUNK = 1 << 16


class SceneGeometry:
    """GPU buffers of a scene's triangles plus each object's topology.  Call `release()`.

    bounds : (n_objects, 2, 3) float64 axis-aligned box (min, max) of each object (world)
    extent : float, the scene's length scale (`Scene.extent`)
    origin : (3,) float64, the world point the GPU's positions are measured from (`move_to`)
    face_normals32 : (M, 3) float32, every triangle's world unit normal (computed in float64,
        rounded once), for the lighting and the ground truth's normal
    triangle_objects : (M,) int32, every triangle's object

    The positions are not kept on the host: every buffer that holds them is written from the
    scene's own float64 vertices and faces, CHUNK triangles at a time (`frame_corners` gives
    any of them as uploaded).
    """

    def __init__(self, ctx: moderngl.Context, scene: Scene):
        self.ctx = ctx
        limit = ctx.info["GL_MAX_TEXTURE_SIZE"]
        if len(scene.objects) > limit:  # the materials are a texture of a row per object
            raise SceneError("objects", f"{len(scene.objects):,} objects, more than this GL "
                                        f"allows ({limit:,}: the rasterizer keeps each object's "
                                        "material in one row of a texture); merge objects")
        self.origin = frame_origin(scene.camera)
        self.moves = 0   # how many times `move_to` rewrote the buffers (their version)
        # the huge triangles cut for the current view (`set_view`): holes (h,) int64 sorted,
        # piece_of (P,) int64 each piece's triangle, pieces (P, 3, 3) float32 in the frame;
        # cuts counts the changes (the near caps' index lists depend on them)
        self.holes = np.zeros(0, np.int64)
        self.piece_of = np.zeros(0, np.int64)
        self.pieces = np.zeros((0, 3, 3), np.float32)
        self.cuts = 0
        self.guard = None   # (planes (5, 4), near) of the last `set_view`
        self.views = 0      # how many times `set_view` was called (the view's version)
        self.far_objects = np.zeros(0, np.int64)   # objects that may hold huge triangles
        # the scene's own arrays (no copies): (n, 3) float64 world vertices, (m, 3) faces
        self._objects = tuple((o.vertices, o.faces) for o in scene.objects)
        counts = [len(f) for _, f in self._objects]
        firsts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
        self.ranges = tuple(ObjectRange(i, int(f), int(c))
                            for i, (f, c) in enumerate(zip(firsts, counts)))
        # the same ranges as arrays, for the per-frame draws (`spans`: no Python per object)
        self.range_first = firsts
        self.range_count = np.asarray(counts, np.int64)
        self.triangle_count = int(sum(counts))
        if self.triangle_count >= MAX_TRIANGLES:
            raise RenderError(f"{self.triangle_count:,} triangles: the rasterizer keys each "
                              f"pixel's triangle by a float32, at most {MAX_TRIANGLES - 1:,}")
        self.topologies = tuple(Topology.build(o.vertices, o.faces) for o in scene.objects)
        self.bounds = np.array([[o.vertices.min(axis=0), o.vertices.max(axis=0)]
                                for o in scene.objects])
        self.extent = scene.extent  # a property of the scene that walks every vertex: once
        # the shadow switches (`Object.cast_shadows`, `receive_shadows`): (n_objects,) bool
        self.casts = np.array([o.cast_shadows for o in scene.objects], bool)
        self.receives = np.array([o.receive_shadows for o in scene.objects], bool)
        self._reach: dict[int, np.ndarray] = {}     # per far object, its triangles' reach
        self._far_corners: dict[int, np.ndarray] = {}   # and its frame corners (`set_view`)
        self._corners64: np.ndarray | None = None   # `soup_corners_f64`, made on first use
        self._buffers = []
        # per triangle: its world-space unit normal, in float64 then rounded once, and its
        # object: the lighting's (the per-triangle data, `in_normal`) and the ground truth's
        # (`truth.truth_pass.surface_outputs`)
        self.face_normals32 = np.empty((self.triangle_count, 3), np.float32)
        for rng, (v, f) in zip(self.ranges, self._objects):
            for a in range(0, rng.count, CHUNK):
                self.face_normals32[rng.first + a:rng.first + a + len(f[a:a + CHUNK])] = \
                    _unit_normals(np.take(v, f[a:a + CHUNK], axis=0))
        self.triangle_objects = np.repeat(np.arange(len(counts), dtype=np.int32), counts)
        self._soup: dict[str, moderngl.Buffer] = {}
        # per triangle, std430 vec4 pairs: (unit normal, object index), (first corner, 0);
        # float32 as the soup's flat attributes were, so the lighting pass sees the same numbers
        self.triangle_data = self._new_buffer("triangle_data")
        materials = np.zeros((len(scene.objects), 3, 4), np.float32)
        for i, o in enumerate(scene.objects):
            m = o.material
            materials[i, 0, :3], materials[i, 1, :3] = m.ambient, m.diffuse
            materials[i, 2, :3], materials[i, 2, 3] = m.specular, m.shininess
        # textures and vertex colours: `surface` says the scene has some (the G-buffer then
        # holds UVs and colours, `target.Target`); texel 3 of a material row holds its
        # texture's index (-1: none)
        self._surface = {"in_uv": tuple(o.uv for o in scene.objects),
                         "in_colour": tuple(o.colors for o in scene.objects)}
        self.surface = any(o.material.texture is not None or o.colors is not None
                           for o in scene.objects)
        textures, index = texture_index(scene)
        materials = np.concatenate([materials, np.zeros((len(scene.objects), 1, 4),
                                                        np.float32)], axis=1)
        materials[:, 3, 0] = index
        self.textures = SceneTextures(ctx, textures) if self.surface else None
        self.materials = ctx.texture((4, len(scene.objects)), 4, materials.tobytes(), dtype="f4")
        self.materials.filter = (moderngl.NEAREST, moderngl.NEAREST)

    def _new_buffer(self, name: str) -> moderngl.Buffer:
        """A buffer of the soup's data `name` (and the pieces' after it), written in chunks."""
        buf = self.ctx.buffer(reserve=max(self.triangle_count * _BYTES[name], 4))
        self._buffers.append(buf)
        self._write_soup([(name, buf)])
        if len(self.piece_of):
            self._write_pieces(buf, name)
        return buf

    def _soup_buffer(self, name: str) -> moderngl.Buffer:
        """The soup's attribute `name`, uploaded on first use."""
        if name not in self._soup:
            self._soup[name] = self._new_buffer(name)
        return self._soup[name]

    def _write_soup(self, targets: list[tuple[str, moderngl.Buffer]]) -> None:
        """Write the soup's data `name` (a key of _BYTES) into `buf` for each (name, buf) of
        `targets`, in the current frame, CHUNK triangles at a time (each chunk's corners
        framed once for all of them)."""
        framed = any(name in _FRAMED for name, _ in targets)
        for rng, (v, f) in zip(self.ranges, self._objects):
            # the vertices framed, then gathered: the same float32 numbers as framing every
            # corner (an elementwise subtraction and rounding), at a fraction of the work
            vertices = to_frame(v, self.origin) if framed else None
            for a in range(0, rng.count, CHUNK):
                faces = f[a:a + CHUNK]
                t = slice(rng.first + a, rng.first + a + len(faces))
                corners = np.take(vertices, faces, axis=0) if framed else None
                for name, buf in targets:
                    data = self._vertex_data(name, rng.index, faces) if name in _SURFACE \
                        else self._data(name, t, corners)
                    buf.write(data, offset=t.start * _BYTES[name])

    def _vertex_data(self, name: str, i: int, faces: np.ndarray) -> np.ndarray:
        """(3 k, C) float32: the surface attribute `name` of object i at the corners of its
        triangles `faces` (k, 3) (UVs 0 and colours 1 where the object has none)."""
        values = self._surface[name][i]
        if values is None:
            fill = 0.0 if name == "in_uv" else 1.0
            return np.full((3 * len(faces), _SURFACE[name]), fill, np.float32)
        return np.take(values, faces.reshape(-1), axis=0).astype(np.float32)

    def _piece_attribute(self, name: str) -> np.ndarray:
        """(3 P, C) float32: the surface attribute `name` at the pieces' corners, interpolated
        in float64 with their barycentrics in their triangle (`set_view`)."""
        out = np.empty((len(self.piece_of), 3, _SURFACE[name]), np.float32)
        objects = self.triangle_objects[self.piece_of]
        tri = self.frame_corners(self.piece_of).astype(np.float64)
        for i in np.unique(objects):
            mine = np.flatnonzero(objects == i)
            faces = self._objects[i][1][self.piece_of[mine] - self.ranges[i].first]
            corner = self._vertex_data(name, int(i), faces).reshape(-1, 3, _SURFACE[name])
            for c in range(3):
                w = _barycentrics(tri[mine], self.pieces[mine, c].astype(np.float64))
                out[mine, c] = np.einsum("kc,kcd->kd", w, corner.astype(np.float64))
        return out.reshape(-1, _SURFACE[name])

    def _data(self, name: str, t, corners: np.ndarray | None) -> np.ndarray:
        """The data `name` of triangles `t` (a slice or (k,) soup indices) whose frame corners
        are `corners` (k, 3, 3) float32 (None unless `name` is in _FRAMED)."""
        if name == "in_position":
            return corners.reshape(-1, 3)
        if name == "in_corner":
            return np.repeat(corners[:, 0], 3, axis=0)
        if name == "in_normal":
            return np.repeat(self.face_normals32[t], 3, axis=0)
        if name == "in_object":
            return np.repeat(self.triangle_objects[t], 3)
        out = np.zeros((len(corners), 2, 4), np.float32)         # triangle_data
        out[:, 0, :3] = self.face_normals32[t]
        out[:, 0, 3] = self.triangle_objects[t]
        out[:, 1, :3] = corners[:, 0]
        return out

    def frame_corners(self, triangles: np.ndarray | None = None) -> np.ndarray:
        """(k, 3, 3) float32: the corners of `triangles` ((k,) soup indices; default every
        triangle, (M, 3, 3)) in the current frame, exactly as uploaded.  Computed from the
        scene's float64 vertices on each call, not kept."""
        if triangles is None:
            out = np.empty((self.triangle_count, 3, 3), np.float32)
            for rng, (v, f) in zip(self.ranges, self._objects):
                np.take(to_frame(v, self.origin), f, axis=0,
                        out=out[rng.first:rng.first + rng.count])
            return out
        triangles = np.asarray(triangles, np.int64)
        out = np.empty((len(triangles), 3, 3), np.float32)
        objects = self.triangle_objects[triangles]
        for i in np.unique(objects):
            mine = objects == i
            v, f = self._objects[i]
            faces = f[triangles[mine] - self.ranges[i].first]
            out[mine] = to_frame(np.take(v, faces, axis=0), self.origin)
        return out

    def _object_frame_corners(self, i: int) -> np.ndarray:
        """(count, 3, 3) float32: object i's frame corners, kept for a far object until the
        frame moves (`set_view` tests them every frame)."""
        if i not in self._far_corners:
            v, f = self._objects[i]
            self._far_corners[i] = np.take(to_frame(v, self.origin), f, axis=0)
        return self._far_corners[i]

    def _piece_data(self, name: str) -> np.ndarray:
        """The data `name` of the pieces (three vertices each; one per-triangle record): their
        own positions, the rest their triangle's."""
        if name == "in_position":
            return self.pieces.reshape(-1, 3)
        if name in _SURFACE:
            return self._piece_attribute(name)
        t = self.piece_of
        return self._data(name, t, self.frame_corners(t) if name in _FRAMED else None)

    def _write_pieces(self, buf: moderngl.Buffer, name: str) -> None:
        """Put the pieces' `name` after the soup's data in `buf`, growing it if needed."""
        tail = np.ascontiguousarray(self._piece_data(name))
        base = self.triangle_count * _BYTES[name]
        if base + tail.nbytes > buf.size:
            buf.orphan(base + tail.nbytes)
            self._write_soup([(name, buf)])
        if tail.nbytes:
            buf.write(tail, offset=base)

    def set_view(self, view_proj: np.ndarray, near: float) -> None:
        """Cut the triangles that reach far outside this view to its guard band (`guard`),
        for the frame's draws.  view_proj : (4, 4) float64 frame -> clip; near : the near
        distance.  Call after `move_to`."""
        planes = guard.guard_planes(view_proj, near)
        self.guard = (planes, near)   # for the volumes' side triangles (`CpuVolumes`)
        self.views += 1
        # only an object whose box reaches beyond HUGE_REACH near distances from the eye can
        # hold a huge triangle: the per-triangle test runs on those objects alone
        box_reach = np.linalg.norm(np.maximum(np.abs(self.bounds[:, 0] - self.origin),
                                              np.abs(self.bounds[:, 1] - self.origin)), axis=1)
        self.far_objects = np.flatnonzero(box_reach > guard.HUGE_REACH * near)
        if len(self.far_objects) == 0 and len(self.holes) == 0:
            return
        found = [np.zeros(0, np.int64)]
        for i in self.far_objects:
            rng = self.ranges[i]
            corners = self._object_frame_corners(int(i))
            if i not in self._reach:
                self._reach[i] = guard.reach(corners)
            found.append(guard.huge(corners, self._reach[i], planes, near) + rng.first)
        holes = np.concatenate(found)
        if len(holes) == 0 and len(self.holes) == 0:
            return
        cut = [guard.cut(c.astype(np.float64), planes) for c in self.frame_corners(holes)]
        self.holes = holes
        self.piece_of = np.repeat(holes, [len(c) for c in cut]).astype(np.int64)
        self.pieces = (np.concatenate(cut) if cut else np.zeros((0, 3, 3))).astype(np.float32)
        if self.triangle_count + len(self.pieces) >= MAX_TRIANGLES:
            raise RenderError(f"{self.triangle_count + len(self.pieces):,} triangles with the "
                              f"pieces of huge ones: at most {MAX_TRIANGLES - 1:,}")
        self.cuts += 1
        for name, buf in self._soup.items():
            self._write_pieces(buf, name)
        self._write_pieces(self.triangle_data, "triangle_data")

    def spans(self, objects, pieces: bool = True) -> list[tuple[int, int]]:
        """(first, count) triangle spans of the draws of `objects` (ascending indices): their
        soup triangles but the holes, then (`pieces`) their pieces (keys M..): the maximal
        runs of consecutive keys, one draw each.  In numpy, whatever the number of objects."""
        if isinstance(objects, range):
            objects = np.arange(objects.start, objects.stop, objects.step, dtype=np.int64)
        objects = np.asarray(objects, np.int64).reshape(-1)
        first = self.range_first[objects]
        end = first + self.range_count[objects]
        starts, ends = merged_runs(first, end)
        if len(self.holes) and len(starts):
            # the holes inside the runs (those of `objects`) split them: [a, h), [h + 1, b)
            run = np.searchsorted(starts, self.holes, side="right") - 1
            holes = self.holes[(run >= 0) & (self.holes < ends[np.maximum(run, 0)])]
            starts = np.sort(np.concatenate([starts, holes + 1]))
            ends = np.sort(np.concatenate([holes, ends]))
            starts, ends = starts[ends > starts], ends[ends > starts]
        if pieces and len(self.piece_of):
            keys = self.triangle_count + np.flatnonzero(
                np.isin(self.triangle_objects[self.piece_of], objects))
            more, more_ends = merged_runs(keys, keys + 1)
            if len(more) and len(ends) and ends[-1] == more[0]:   # the soup's run goes on
                ends = np.concatenate([ends[:-1], more_ends[:1]])
                more, more_ends = more[1:], more_ends[1:]
            starts = np.concatenate([starts, more])
            ends = np.concatenate([ends, more_ends])
        return list(zip(starts.tolist(), (ends - starts).tolist()))

    def pieces_of(self, triangles: np.ndarray) -> np.ndarray:
        """(k,) int64 keys: `triangles` (soup indices) with each hole replaced by the keys of its
        pieces (M..)."""
        if len(self.holes) == 0:
            return triangles
        cut = np.isin(triangles, self.holes)
        extra = self.triangle_count + np.flatnonzero(np.isin(self.piece_of, triangles[cut]))
        return np.concatenate([triangles[~cut], extra])

    def triangle_of_key(self, keys: np.ndarray) -> np.ndarray:
        """The soup triangle of each G-buffer key (a piece's key -> its triangle; -1 stays)."""
        if len(self.piece_of) == 0:
            return keys
        piece = keys >= self.triangle_count
        out = keys.copy()
        out[piece] = self.piece_of[keys[piece] - self.triangle_count]
        return out

    def move_to(self, origin: np.ndarray) -> bool:
        """Express the GPU's positions in the frame of `origin` (3,) float64 (a frame's
        `frame_origin`), rewriting the buffers that hold positions if it moved.  Returns
        whether it moved.  Volumes check `moves` and rewrite their own buffers on use."""
        origin = np.asarray(origin, np.float64)
        if np.array_equal(origin, self.origin):
            return False
        self.origin = origin.copy()
        self.moves += 1
        self._reach, self._far_corners = {}, {}
        self._write_soup([(name, buf) for name, buf in self._soup.items() if name in _FRAMED]
                         + [("triangle_data", self.triangle_data)])
        return True

    @property
    def positions(self) -> moderngl.Buffer:
        """The soup's vertex positions (float32, three per triangle)."""
        return self._soup_buffer("in_position")

    @property
    def soup_corners_f64(self) -> np.ndarray:
        """(M, 3, 3) float64: every triangle's world corners, objects one after another (the
        stencil-overflow bounds' input: made on first use and kept)."""
        if self._corners64 is None:
            self._corners64 = np.concatenate([np.take(v, f, axis=0) for v, f in self._objects])
        return self._corners64

    @property
    def object_of(self) -> np.ndarray:
        """(M,) int64: the object of every triangle."""
        return np.repeat(np.arange(len(self.ranges)), [r.count for r in self.ranges])

    def soup_corners(self) -> np.ndarray:
        """(M, 3, 3) float32: the corners of every soup triangle in the current frame, exactly
        as uploaded (computed, not kept: `frame_corners`)."""
        return self.frame_corners()

    def soup_bindings(self, program: moderngl.Program) -> list[tuple]:
        """The (buffer, format, name) triples of the soup's attributes that `program` uses."""
        formats = {"in_position": "3f", "in_normal": "3f", "in_corner": "3f", "in_object": "1i",
                   "in_uv": "2f", "in_colour": "3f"}
        return [(self._soup_buffer(name), fmt, name) for name, fmt in formats.items()
                if name in program]

    def release(self) -> None:
        for buf in self._buffers:
            buf.release()
        self._buffers.clear()
        self.materials.release()
        if self.textures is not None:
            self.textures.release()


def merged_runs(first: np.ndarray, end: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The ranges [first, end) in their order, empty ones dropped and each merged with the
    one it continues (first == the previous end): (starts, ends) of the runs, int64."""
    keep = end > first
    first, end = first[keep].astype(np.int64), end[keep].astype(np.int64)
    if not len(first):
        return first, end
    cut = np.flatnonzero(first[1:] != end[:-1]) + 1
    return (first[np.concatenate([[0], cut])],
            end[np.concatenate([cut - 1, [len(end) - 1]])])


def _barycentrics(corners: np.ndarray, p: np.ndarray) -> np.ndarray:
    """(k, 3) float64 barycentric weights of points p (k, 3) in triangles corners (k, 3, 3)."""
    a = corners[:, 0]
    e1, e2, q = corners[:, 1] - a, corners[:, 2] - a, p - a
    d11, d12, d22 = (e1 * e1).sum(1), (e1 * e2).sum(1), (e2 * e2).sum(1)
    dq1, dq2 = (q * e1).sum(1), (q * e2).sum(1)
    den = d11 * d22 - d12 * d12
    den = np.where(den == 0.0, 1.0, den)
    b1, b2 = (d22 * dq1 - d12 * dq2) / den, (d11 * dq2 - d12 * dq1) / den
    return np.stack([1.0 - b1 - b2, b1, b2], axis=1)


def _unit_normals(corners: np.ndarray) -> np.ndarray:
    """(k, 3, 3) float64 corners -> (k, 3) float64 unit normals (b - a) x (c - a); 0 for a
    degenerate triangle."""
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)
