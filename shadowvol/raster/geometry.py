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
"""

from __future__ import annotations

from dataclasses import dataclass

import moderngl
import numpy as np

from shadowvol.cameras import frame_origin
from shadowvol.errors import RenderError
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
            if name in _FRAMED:
                data = self._framed(name)
            elif name == "in_normal":
                data = np.repeat(self._normals, 3, axis=0).astype(np.float32)
            else:
                data = np.repeat(np.arange(len(self.ranges), dtype=np.int32),
                                 [3 * r.count for r in self.ranges])
            self._soup[name] = self._buffer(data)
        return self._soup[name]

    def _framed(self, name: str) -> np.ndarray:
        """The soup attribute `name` (one of _FRAMED) in the current frame, float32."""
        if name == "in_position":
            return to_frame(self._corners.reshape(-1, 3), self.origin)
        return np.repeat(to_frame(self._corners[:, 0], self.origin), 3, axis=0)

    def move_to(self, origin: np.ndarray) -> bool:
        """Express the GPU's positions in the frame of `origin` (3,) float64 (a frame's
        `frame_origin`), rewriting the buffers that hold positions if it moved.  Returns
        whether it moved.  Volumes check `moves` and rewrite their own buffers on use."""
        origin = np.asarray(origin, np.float64)
        if np.array_equal(origin, self.origin):
            return False
        self.origin = origin.copy()
        self.moves += 1
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
        return to_frame(self._corners, self.origin)

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
