"""Unprojecting the ray tracer's `depth` with `K` and `camera_to_world` and reprojecting into a
second camera with its `K` and `world_to_camera` lands on the same object's pixels, sub-pixel,
on a real mesh (Keenan Crane's spot, from ../shared/models).  Only the stored matrices are used,
as a dataset user would, never the ray tracer's own rays."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from builders import MODELS

from raytrace.groundtruth import ground_truth
from shadowvol.cameras import project, unproject
from shadowvol.compare.maskdiff import edge_pixels
from shadowvol.primitives import mesh, plane
from shadowvol.scene import Camera, DirectionalLight, Material, Scene

# How far (pixels) a reprojected point may land from where the second view sees the same
# surface point: bilinear interpolation of that view's unprojected points between pixel
# centres, on a mesh whose triangles are a few pixels wide.  A principal point off by half a
# pixel moves every point by 0.5.
MEDIAN_PIXELS = 0.02
WORST_PIXELS = 0.25


@pytest.fixture(scope="module")
def spot() -> Path:
    path = MODELS / "spot.obj"
    if not MODELS.is_dir():
        pytest.skip(f"the shared test meshes are missing: {MODELS} does not exist")
    if not path.is_file():
        pytest.fail(f"{path} is missing from the shared models folder")
    return path


def two_views(path: Path, width=200, height=150) -> tuple[Scene, Scene]:
    import trimesh

    loaded = trimesh.load(str(path), process=False)
    v = np.asarray(loaded.vertices, np.float64)
    v = (v - v.mean(axis=0)) * (1.5 / np.ptp(v, axis=0).max())
    v[:, 1] -= v[:, 1].min()
    cow = mesh("spot", v, np.asarray(loaded.faces), Material())
    first = Scene(camera=Camera(eye=[0.6, 1.6, 2.6], target=[0.0, 0.6, 0.0], fov_y=45.0),
                  objects=[plane("floor", size=[6, 6]), cow],
                  lights=[DirectionalLight([0.3, -1.0, -0.2])], width=width, height=height)
    second = first.replace(camera=Camera(eye=[-2.2, 1.2, 1.4], target=[0.1, 0.5, -0.1],
                                         fov_y=38.0), width=180, height=160)
    return first, second


def bilinear(points: np.ndarray, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """points (H, W, 3) sampled at pixel centres, read at continuous (u, v): (n, 3), and the
    four pixels' (y, x) corners (n, 4, 2)."""
    x, y = u - 0.5, v - 0.5
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]
    p = (points[y0, x0] * (1 - fx) * (1 - fy) + points[y0, x0 + 1] * fx * (1 - fy)
         + points[y0 + 1, x0] * (1 - fx) * fy + points[y0 + 1, x0 + 1] * fx * fy)
    corners = np.stack([np.stack([y0, x0], -1), np.stack([y0, x0 + 1], -1),
                        np.stack([y0 + 1, x0], -1), np.stack([y0 + 1, x0 + 1], -1)], axis=1)
    return p, corners


def test_depth_reprojects_into_a_second_view_on_the_same_object(spot):
    first, second = two_views(spot)
    a = ground_truth(first, ["depth", "object_id"])
    b = ground_truth(second, ["depth", "object_id"])
    ca, cb = a.calibration, b.calibration
    # the same view: back onto its own pixel centres
    world = unproject(ca.K, ca.camera_to_world, a.depth)
    seen = a.object_id > 0
    uv = project(ca.K, ca.world_to_camera, world[seen])
    ys, xs = np.nonzero(seen)
    np.testing.assert_allclose(uv, np.stack([xs + 0.5, ys + 0.5], -1), atol=1e-6)

    # into the second view: where it sees that point (nothing nearer in front of it) the
    # object is the same and the point is where the second view's own unprojection puts it
    uv = project(cb.K, cb.world_to_camera, world[seen])
    inside = ((uv[:, 0] > 1) & (uv[:, 0] < second.width - 1) & (uv[:, 1] > 1)
              & (uv[:, 1] < second.height - 1))
    uv, points, ids = uv[inside], world[seen][inside], a.object_id[seen][inside]
    x, y = uv[:, 0].astype(int), uv[:, 1].astype(int)
    z = (points @ cb.world_to_camera[:3, :3].T + cb.world_to_camera[:3, 3])[:, 2]
    visible = z <= b.depth[y, x] * (1 + 1e-3)  # not behind what view b sees there
    assert visible.sum() > 3000
    edges = np.logical_or.reduce([edge_pixels(b.object_id == k) for k in range(3)])
    clear = visible & ~edges[y, x]
    assert (b.object_id[y, x][clear] == ids[clear]).all()
    assert (ids[clear] == 2).sum() > 1000  # the cow itself, not only the floor

    # sub-pixel: compare with the second view's unprojected points, bilinear between the four
    # pixel centres around (u, v), where all four see the same object and the depth is smooth
    world_b = unproject(cb.K, cb.camera_to_world, b.depth)
    q, corners = bilinear(np.nan_to_num(world_b), uv[:, 0], uv[:, 1])
    corner_ids = b.object_id[corners[..., 0], corners[..., 1]]
    corner_depth = b.depth[corners[..., 0], corners[..., 1]]
    smooth = (visible & (corner_ids == ids[:, None]).all(axis=1)
              & (np.ptp(corner_depth, axis=1) < 0.01 * corner_depth.min(axis=1)))
    assert smooth.sum() > 2000
    # the distance between the two points, in the second view's pixels at that depth
    error = np.linalg.norm(q[smooth] - points[smooth], axis=1) * cb.K[0, 0] / z[smooth]
    assert np.median(error) < MEDIAN_PIXELS, np.median(error)
    assert np.quantile(error, 0.99) < WORST_PIXELS, np.quantile(error, 0.99)
