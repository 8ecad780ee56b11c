"""What a renderer keeps in host memory besides the GL's buffers: no copy of what it uploaded.

On a software GL (llvmpipe) every buffer is host memory already, so an array kept after its
upload is a second copy of it.  The geometry keeps per triangle only what the frames read on
the host (the float32 unit normal and the object: 16 bytes), its topologies int32 indices;
the positions, first corners and per-triangle records are written to the GL and recomputed
from the scene's float64 vertices when they are needed (`SceneGeometry.frame_corners`).
"""

from __future__ import annotations

import numpy as np
import pytest

from shadowvol.primitives import plane, sphere
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import Camera, PointLight, Scene


def _scene() -> Scene:
    balls = [sphere(f"ball{i}", [2.0 * i - 3.0, 1.0, 0.0], 0.8, subdivisions=3)
             for i in range(4)]
    return Scene(camera=Camera(eye=[0.0, 4.0, 9.0], target=[0.0, 0.8, 0.0]),
                 objects=[plane("floor", size=[14, 14])] + balls,
                 lights=[PointLight([2.0, 6.0, 3.0])], width=64, height=48)


def _arrays(obj, seen=None, path="geometry"):
    """(path, array) of every numpy array reachable from `obj`'s attributes, through dicts,
    lists, tuples and the attributes of objects of shadowvol's own classes."""
    seen = set() if seen is None else seen
    if id(obj) in seen:
        return
    seen.add(id(obj))
    if isinstance(obj, np.ndarray):
        yield path, obj
    elif isinstance(obj, dict):
        for k, v in obj.items():
            yield from _arrays(v, seen, f"{path}[{k!r}]")
    elif isinstance(obj, (list, tuple)):
        for i, v in enumerate(obj):
            yield from _arrays(v, seen, f"{path}[{i}]")
    elif type(obj).__module__.startswith("shadowvol") and hasattr(obj, "__dict__"):
        for k, v in vars(obj).items():
            yield from _arrays(v, seen, f"{path}.{k}")


@pytest.mark.parametrize("silhouettes", ["cpu", "gpu"])
def test_the_geometry_keeps_no_host_copy_of_its_uploads(ctx, silhouettes):
    scene = _scene()
    moved = Camera(eye=[3.0, 5.0, 7.0], target=[0.0, 0.5, 0.0])
    with Renderer(scene, ctx) as r:
        r.render(silhouettes=silhouettes)
        r.render(silhouettes=silhouettes, camera=moved)   # a move rewrites the buffers
        geometry = r.geometry
        m = geometry.triangle_count
        # the scene's own arrays are the scene's, not copies
        owned = {id(a) for o in scene.objects for a in (o.vertices, o.faces)}
        kept = [(p, a) for p, a in _arrays(geometry)
                if id(a) not in owned and ".topologies" not in p]
        big = [(p, a.dtype, a.shape) for p, a in kept if a.nbytes > 12 * m]
        assert not big, f"arrays larger than a float32 vector per triangle: {big}"
        assert sum(a.nbytes for _, a in kept) <= 16 * m + 4096, \
            [(p, a.nbytes) for p, a in kept if a.nbytes > 1024]
        # what was uploaded is recomputed bit for bit
        uploaded = np.frombuffer(geometry.positions.read(), np.float32)[:9 * m]
        np.testing.assert_array_equal(uploaded, geometry.frame_corners().reshape(-1))
        some = np.array([m - 1, 0, m // 2])
        np.testing.assert_array_equal(geometry.frame_corners(some),
                                      geometry.frame_corners()[some])
        for topo in geometry.topologies:
            for name in ("remap", "faces", "edges", "inc_edge", "inc_face", "inc_opposite"):
                assert getattr(topo, name).dtype == np.int32, name
