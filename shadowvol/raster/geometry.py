"""The scene's geometry on the GPU, uploaded once per scene.

All objects become one triangle soup (three vertices per triangle, objects one after another) so
that every per-triangle value can be a flat vertex attribute: the face normal, the first corner
(for the triangle's n . l sign) and the object index (the row of the material texture).  The
depth pass, the lighting pass and the z-fail near caps all draw from these buffers.

float32 is used on the GPU because that is what GL rasterizes; normals and corners are computed
in float64 and rounded once.  Edge topology (CPU, float64) is computed here too, once per object.
"""

from __future__ import annotations

from dataclasses import dataclass

import moderngl
import numpy as np

from shadowvol.raster.topology import Topology
from shadowvol.scene import Scene


@dataclass(frozen=True)
class ObjectRange:
    """Where object `index` lives in the soup: triangles [first, first + count)."""

    index: int
    first: int
    count: int


class SceneGeometry:
    """GPU buffers of a scene's triangles plus each object's topology.  Call `release()`.

    bounds : (n_objects, 2, 3) float64 axis-aligned box (min, max) of each object
    extent : float, the scene's length scale (`Scene.extent`)
    """

    def __init__(self, ctx: moderngl.Context, scene: Scene):
        self.ctx = ctx
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
        object_ids = np.repeat(np.arange(len(tris), dtype=np.int32), np.array(counts) * 3)
        self.topologies = tuple(Topology.build(o.vertices, o.faces) for o in scene.objects)
        self.bounds = np.array([[o.vertices.min(axis=0), o.vertices.max(axis=0)]
                                for o in scene.objects])
        self.extent = scene.extent  # a property of the scene that walks every vertex: once
        self._buffers = []
        self.positions = self._buffer(corners.reshape(-1, 3).astype(np.float32))
        self.normals = self._buffer(np.repeat(normals, 3, axis=0).astype(np.float32))
        self.corners = self._buffer(np.repeat(corners[:, 0], 3, axis=0).astype(np.float32))
        self.objects = self._buffer(object_ids)
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

    def soup_corners(self) -> np.ndarray:
        """(M, 3, 3) float32: the corners of every soup triangle, exactly as uploaded."""
        return self._corners.astype(np.float32)

    def soup_bindings(self, program: moderngl.Program) -> list[tuple]:
        """The (buffer, format, name) triples of the soup's attributes that `program` uses."""
        all_ = [(self.positions, "3f", "in_position"), (self.normals, "3f", "in_normal"),
                (self.corners, "3f", "in_corner"), (self.objects, "1i", "in_object")]
        return [b for b in all_ if b[2] in program]

    def release(self) -> None:
        for buf in self._buffers:
            buf.release()
        self._buffers.clear()
        self.materials.release()
