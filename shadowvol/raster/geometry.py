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
per-triangle data) in place; normals, objects and the float64 world corners and topology stay.
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
from shadowvol.raster.topology import Topology
from shadowvol.scene import Scene

MAX_TRIANGLES = 2 ** 24  # the G-buffer's surface key is a float32 integer (target.py)


@dataclass(frozen=True)
class ObjectRange:
    """Where object `index` lives in the soup: triangles [first, first + count)."""

    index: int
    first: int
    count: int


# the soup's attributes that hold positions, rewritten when the frame moves
_FRAMED = ("in_position", "in_corner")


class SceneGeometry:
    """GPU buffers of a scene's triangles plus each object's topology.  Call `release()`.

    bounds : (n_objects, 2, 3) float64 axis-aligned box (min, max) of each object (world)
    extent : float, the scene's length scale (`Scene.extent`)
    origin : (3,) float64, the world point the GPU's positions are measured from (`move_to`)
    """

    def __init__(self, ctx: moderngl.Context, scene: Scene):
        self.ctx = ctx
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
        tris = [o.triangles for o in scene.objects]                       # (m, 3, 3) each
        corners = np.concatenate(tris)                                    # (M, 3, 3) float64
        self._corners = corners
        normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        length = np.linalg.norm(normals, axis=1, keepdims=True)
        normals = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)
        counts = [len(t) for t in tris]
        firsts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        self.ranges = tuple(ObjectRange(i, int(f), int(c))
                            for i, (f, c) in enumerate(zip(firsts, counts)))
        self.triangle_count = int(sum(counts))
        if self.triangle_count >= MAX_TRIANGLES:
            raise RenderError(f"{self.triangle_count:,} triangles: the rasterizer keys each "
                              f"pixel's triangle by a float32, at most {MAX_TRIANGLES - 1:,}")
        self.topologies = tuple(Topology.build(o.vertices, o.faces) for o in scene.objects)
        self.bounds = np.array([[o.vertices.min(axis=0), o.vertices.max(axis=0)]
                                for o in scene.objects])
        self.extent = scene.extent  # a property of the scene that walks every vertex: once
        self._frame_corners()
        self._buffers = []
        self._normals = normals
        # per triangle: its world-space unit normal (float64) and its object, for the ground
        # truth's normal and object id (`truth.surface_outputs`)
        self.face_normals = normals
        self.face_normals32 = normals.astype(np.float32)
        self.triangle_objects = np.repeat(np.arange(len(tris), dtype=np.int64), counts)
        self._soup: dict[str, moderngl.Buffer] = {}
        # per triangle, std430 vec4 pairs: (unit normal, object index), (first corner, 0);
        # float32 as the soup's flat attributes were, so the lighting pass sees the same numbers
        per_triangle = np.zeros((self.triangle_count, 2, 4), np.float32)
        per_triangle[:, 0, :3] = normals
        per_triangle[:, 0, 3] = np.repeat(np.arange(len(tris)), counts)
        per_triangle[:, 1, :3] = to_frame(corners[:, 0], self.origin)
        self._per_triangle = per_triangle
        self.triangle_data = self._buffer(per_triangle)
        materials = np.zeros((len(scene.objects), 3, 4), np.float32)
        for i, o in enumerate(scene.objects):
            m = o.material
            materials[i, 0, :3], materials[i, 1, :3] = m.ambient, m.diffuse
            materials[i, 2, :3], materials[i, 2, 3] = m.specular, m.shininess
        self.materials = ctx.texture((3, len(scene.objects)), 4, materials.tobytes(), dtype="f4")
        self.materials.filter = (moderngl.NEAREST, moderngl.NEAREST)

    def _buffer(self, data: np.ndarray) -> moderngl.Buffer:
        buf = self.ctx.buffer(np.ascontiguousarray(data).tobytes())
        self._buffers.append(buf)
        return buf

    def _soup_buffer(self, name: str) -> moderngl.Buffer:
        """The soup's attribute `name`, uploaded on first use."""
        if name not in self._soup:
            data = self._soup_base(name)
            self._soup[name] = buf = self._buffer(data)
            if len(self.piece_of):
                self._write_pieces(buf, data, name)
        return self._soup[name]

    def _frame_corners(self) -> None:
        """The float32 corners in the current frame (the far objects' reach is recomputed on
        use)."""
        self.frame_corners = to_frame(self._corners, self.origin)          # (M, 3, 3) float32
        self._reach: dict[int, np.ndarray] = {}   # per far object, its triangles' reach

    def _framed(self, name: str) -> np.ndarray:
        """The soup attribute `name` (one of _FRAMED) in the current frame, float32."""
        if name == "in_position":
            return self.frame_corners.reshape(-1, 3)
        return np.repeat(self.frame_corners[:, 0], 3, axis=0)

    def _piece_data(self, name: str) -> np.ndarray:
        """The attribute `name` of the pieces (three vertices each): their own positions, the
        rest their triangle's."""
        t = self.piece_of
        if name == "in_position":
            return self.pieces.reshape(-1, 3)
        if name == "in_corner":
            return np.repeat(self.frame_corners[t, 0], 3, axis=0)
        if name == "in_normal":
            return np.repeat(self._normals[t], 3, axis=0).astype(np.float32)
        if name == "triangle_data":
            return self._per_triangle[t]
        return np.repeat(self.triangle_objects[t].astype(np.int32), 3)

    def _write_pieces(self, buf: moderngl.Buffer, base: np.ndarray, name: str) -> None:
        """Put the pieces' `name` after the soup's `base` data in `buf`, growing it if needed."""
        tail = np.ascontiguousarray(self._piece_data(name))
        if base.nbytes + tail.nbytes > buf.size:
            buf.orphan(base.nbytes + tail.nbytes)
            buf.write(np.ascontiguousarray(base).tobytes())
        if tail.nbytes:
            buf.write(tail.tobytes(), offset=base.nbytes)

    def _soup_base(self, name: str) -> np.ndarray:
        if name in _FRAMED:
            return self._framed(name)
        if name == "in_normal":
            return np.repeat(self._normals, 3, axis=0).astype(np.float32)
        return np.repeat(self.triangle_objects.astype(np.int32), 3)

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
            corners = self.frame_corners[rng.first:rng.first + rng.count]
            if i not in self._reach:
                self._reach[i] = guard.reach(corners)
            found.append(guard.huge(corners, self._reach[i], planes, near) + rng.first)
        holes = np.concatenate(found)
        if len(holes) == 0 and len(self.holes) == 0:
            return
        cut = [guard.cut(self.frame_corners[t].astype(np.float64), planes) for t in holes]
        self.holes = holes
        self.piece_of = np.repeat(holes, [len(c) for c in cut]).astype(np.int64)
        self.pieces = (np.concatenate(cut) if cut else np.zeros((0, 3, 3))).astype(np.float32)
        if self.triangle_count + len(self.pieces) >= MAX_TRIANGLES:
            raise RenderError(f"{self.triangle_count + len(self.pieces):,} triangles with the "
                              f"pieces of huge ones: at most {MAX_TRIANGLES - 1:,}")
        self.cuts += 1
        for name, buf in self._soup.items():
            self._write_pieces(buf, self._soup_base(name), name)
        self._write_pieces(self.triangle_data, self._per_triangle, "triangle_data")

    def spans(self, objects, pieces: bool = True) -> list[tuple[int, int]]:
        """(first, count) triangle spans of the draws of `objects` (ascending indices): their
        soup triangles but the holes, then (`pieces`) their pieces (keys M..), runs merged."""
        out: list[list[int]] = []

        def add(first: int, count: int) -> None:
            if count <= 0:
                return
            if out and out[-1][0] + out[-1][1] == first:
                out[-1][1] += count
            else:
                out.append([first, count])

        objects = list(objects)
        for i in objects:
            rng = self.ranges[i]
            start, end = rng.first, rng.first + rng.count
            for h in self.holes[(self.holes >= start) & (self.holes < end)]:
                add(start, int(h) - start)
                start = int(h) + 1
            add(start, end - start)
        if pieces and len(self.piece_of):
            mine = np.isin(self.triangle_objects[self.piece_of], objects)
            for k in np.flatnonzero(mine):
                add(self.triangle_count + int(k), 1)
        return [(f, c) for f, c in out]

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
        self._frame_corners()
        for name, buf in self._soup.items():
            if name in _FRAMED:
                buf.write(np.ascontiguousarray(self._framed(name)).tobytes())
        self._per_triangle[:, 1, :3] = to_frame(self._corners[:, 0], origin)
        self.triangle_data.write(self._per_triangle.tobytes())
        return True

    @property
    def positions(self) -> moderngl.Buffer:
        """The soup's vertex positions (float32, three per triangle)."""
        return self._soup_buffer("in_position")

    @property
    def soup_corners_f64(self) -> np.ndarray:
        """(M, 3, 3) float64: every triangle's world corners, objects one after another."""
        return self._corners

    @property
    def object_of(self) -> np.ndarray:
        """(M,) int64: the object of every triangle."""
        return np.repeat(np.arange(len(self.ranges)), [r.count for r in self.ranges])

    def soup_corners(self) -> np.ndarray:
        """(M, 3, 3) float32: the corners of every soup triangle in the current frame, exactly
        as uploaded."""
        return self.frame_corners

    def soup_bindings(self, program: moderngl.Program) -> list[tuple]:
        """The (buffer, format, name) triples of the soup's attributes that `program` uses."""
        formats = {"in_position": "3f", "in_normal": "3f", "in_corner": "3f", "in_object": "1i"}
        return [(self._soup_buffer(name), fmt, name) for name, fmt in formats.items()
                if name in program]

    def release(self) -> None:
        for buf in self._buffers:
            buf.release()
        self._buffers.clear()
        self.materials.release()
