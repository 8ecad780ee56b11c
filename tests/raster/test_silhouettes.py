"""`topology_signs` (normals and first corners kept on the topology) must equal
`triangle_signs` bit for bit: sides and caps of every renderer path rely on one sign per
triangle, and the CPU path's signs must not change with the speed-up."""

from __future__ import annotations

import numpy as np
import pytest

from shadowvol.raster.volumes.silhouettes import topology_signs, triangle_signs
from shadowvol.raster.volumes.topology import Topology


@pytest.mark.parametrize("seed", range(5))
def test_topology_signs_equal_triangle_signs(seed):
    rng = np.random.default_rng(seed)
    vertices = rng.normal(size=(300, 3))
    faces = rng.integers(0, 300, size=(800, 3))
    faces[:20, 1] = faces[:20, 0]                      # degenerate triangles
    vertices[:30, 2] = 0.0                             # triangles in the plane z = 0 ...
    faces[20:40] = rng.integers(0, 30, size=(20, 3))
    topo = Topology.build(vertices, faces)
    lights = [np.append(rng.normal(size=3) * 3, 1.0) for _ in range(5)]
    lights += [np.array([0.3, -0.2, 0.0, 1.0]),         # ... with the light in that plane
               np.array([1.0, 0.5, 0.0, 0.0]),          # a directional light along it
               np.append(rng.normal(size=3), 0.0)]
    for light4 in lights:
        expected = triangle_signs(topo.vertices, topo.faces, light4)
        np.testing.assert_array_equal(topology_signs(topo, light4), expected)
    assert (triangle_signs(topo.vertices, topo.faces, lights[5]) == 0).sum() >= 20
