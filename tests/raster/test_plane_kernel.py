"""`plane_kernel.depths` (numba) against `plane_depth.plane_depths`' numpy path, byte for byte:
random triangles, pixels mapped to them at random, edge-on and degenerate triangles among them
(their pixels keep the fallback), every triangle's plane and a few triangles' (the unique path)."""

from __future__ import annotations

import numpy as np
import pytest

from shadowvol.raster.truth import plane_depth, plane_kernel
from shadowvol.scene import Camera

pytestmark = pytest.mark.skipif(plane_kernel.depths is None, reason="numba not installed")


class _Geometry:
    """What plane_depths reads of a SceneGeometry: the frame corners, their count, the origin."""

    def __init__(self, corners: np.ndarray):
        self.corners, self.origin = corners, np.array([0.5, -0.25, 2.0])
        self.triangle_count = len(corners)

    def frame_corners(self, which=None):
        return self.corners if which is None else self.corners[which]


@pytest.mark.parametrize("count", [50, 5000])   # fewer than the pixels, and more (np.unique)
def test_kernel_matches_numpy(monkeypatch, count):
    rng = np.random.default_rng(count)
    corners = rng.normal(0, 3, (count, 3, 3)).astype(np.float32)
    corners[0] = corners[0, 0]                                   # degenerate: a point
    corners[1, :, 2] = corners[1, 0, 2]                          # edge-on to the +z axis ...
    corners[1, :, 0] = corners[1, 0, 0]                          # ... a segment-like sliver
    geo = _Geometry(corners)
    cam = Camera(eye=(0.3, 1.0, 9.0), target=(0.0, 0.0, 0.0), fov_y=50.0)
    h, w = 37, 53
    tri = rng.integers(-1, count, (h, w))
    tri[:3] = 0
    tri[3:5] = 1
    fallback = rng.random((h, w)).astype(np.float32)
    compiled = plane_depth.plane_depths(geo, cam, tri, fallback)
    monkeypatch.setattr(plane_kernel, "depths", None)
    plain = plane_depth.plane_depths(geo, cam, tri, fallback)
    assert compiled.dtype == plain.dtype == np.float32
    assert compiled.tobytes() == plain.tobytes()
    assert (compiled != fallback).any() and (compiled[:3] == fallback[:3]).all()


class _Surfaces:
    """What surface_outputs reads of a SceneGeometry: float32 normals, each triangle's object."""

    def __init__(self, rng, count: int):
        self.face_normals32 = rng.normal(0, 1, (count, 3)).astype(np.float32)
        self.face_normals32[0] = 0.0                                   # negated: -0.0
        self.triangle_objects = rng.integers(0, 70000, count)          # wraps past uint16


def test_surface_kernel_matches_numpy(monkeypatch):
    from shadowvol.raster.truth import truth_pass

    rng = np.random.default_rng(7)
    geo = _Surfaces(rng, 300)
    triangle = rng.integers(-1, 300, (29, 41))
    front = rng.random((29, 41)) < 0.5
    for want in ({"normal"}, {"object_id"}, {"normal", "object_id"}):
        compiled = truth_pass.surface_outputs(geo, triangle, front, want)
        with monkeypatch.context() as m:
            m.setattr(plane_kernel, "surface", None)
            plain = truth_pass.surface_outputs(geo, triangle, front, want)
        assert compiled.keys() == plain.keys() == want
        for name in want:
            assert compiled[name].dtype == plain[name].dtype
            assert compiled[name].tobytes() == plain[name].tobytes(), name
