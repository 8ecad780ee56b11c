"""Depth and distance far away (issue 31): on a 1e6-unit ground seen at a low angle, every
pixel's depth against the analytic depth of the ground's plane, out to thousands of units.

The depth buffer's float32 1/d, interpolated across a triangle whose corners lie 5e5 away, was
off by up to 3.1e-4 relative at ~6,700 units (4e-5 in this test); the depth is now the
pixel-centre ray met with the G-buffer triangle's plane in float64
(`shadowvol.raster.truth.plane_depth`), as the ray tracer does.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from builders import TEST_OUTPUT

from shadowvol.cameras import look_at_basis
from shadowvol.primitives import plane
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import Camera, DirectionalLight, Scene

# CONVENTIONS' depth tolerance against the exact value (relative): measured 1.3e-7 here (the
# float32 rounding of the result and of the triangle's corners)
DEPTH_RTOL = 1e-6
OUT = TEST_OUTPUT / "raster-depth-far"


def analytic(scene: Scene, height: float) -> tuple[np.ndarray, np.ndarray]:
    """(H, W) float64 depth and distance of the plane y = height at each pixel centre (inf
    where the ray misses it), computed from the camera alone."""
    cam = scene.camera
    right, up, back = look_at_basis(cam)
    h, w = scene.height, scene.width
    half_h = math.tan(math.radians(cam.fov_y) / 2.0)
    x = ((np.arange(w) + 0.5) / w * 2.0 - 1.0) * half_h * (w / h)
    y = (1.0 - (np.arange(h) + 0.5) / h * 2.0) * half_h
    d = right * x[None, :, None] + up * y[:, None, None] - back          # (H, W, 3), depth 1
    with np.errstate(divide="ignore"):
        depth = (height - cam.eye[1]) / d[..., 1]
    depth = np.where(depth > 0, depth, np.inf)
    return depth, depth * np.linalg.norm(d, axis=-1)


@pytest.mark.gl
@pytest.mark.parametrize("offset", [0.0, 1e4])
@pytest.mark.parametrize("fov, slope, farthest", [(50.0, -0.4, 30.0), (3.0, -0.02, 6700.0)])
def test_depth_on_a_huge_ground_is_exact_far_away(ctx, offset, fov, slope, farthest):
    """A 1e6 ground seen from 1.7 m up, the horizon in view (a narrow view: one pixel below it
    is ~7,000 units away): depth and distance within DEPTH_RTOL of the plane's analytic values
    at every covered pixel."""
    eye = np.array([offset, 1.7, offset])
    scene = Scene(camera=Camera(eye=eye, target=eye + [0.3, slope, -1.0], fov_y=fov, near=0.1),
                  objects=[plane("ground", point=[offset, 0.0, offset], size=[1e6, 1e6])],
                  lights=[DirectionalLight([0.2, -1.0, 0.3])], width=160, height=120)
    with Renderer(scene, ctx) as r:
        frame = r.render(outputs=("coverage", "depth", "distance"))
    depth, distance = analytic(scene, 0.0)
    hit = np.isfinite(depth) & frame.coverage
    assert hit.sum() > 5000 and depth[hit].max() > farthest
    for name, want in (("depth", depth), ("distance", distance)):
        got = getattr(frame, name).astype(np.float64)
        err = np.abs(got[hit] / want[hit] - 1)
        if err.max() > DEPTH_RTOL:
            OUT.mkdir(parents=True, exist_ok=True)
            np.savez(OUT / f"{name}-{offset:g}.npz", got=got, want=want)
        worst = np.argmax(err)
        assert err.max() <= DEPTH_RTOL, (name, err.max(), want[hit][worst])
