"""Cameras given by matrices in the ray tracer (docs/CONVENTIONS.md, "Camera matrices").

- The K and camera_to_world a frame writes, read back as its camera (a scene file's `fx`, `fy`,
  `cx`, `cy`, `camera_to_world`), give the same file again bit for bit: masks, every ground
  truth output and the matrices themselves.
- Independent of the renderers: points placed at known pixels by K and camera_to_world in
  float64 (non-square pixels, an off-centre principal point, a turned camera) are seen at
  those pixels, at their depth, with their normal, and unproject back onto themselves.
"""

from __future__ import annotations

import numpy as np
import pytest
from builders import SCENES, camera_from_matrices, cards_scene, off_centre

import raytrace
from shadowvol.cameras import unproject
from shadowvol.cli.raytrace import main as raytrace_main
from shadowvol.scene import Camera, DirectionalLight, Object, Scene
from shadowvol.scenefile import load_scene, save_scene

SIZE = dict(width=96, height=72)
# fronto-parallel squares of this half-size in pixels, centred within MISS pixels of a pixel
# centre: a camera off by more than HALF - MISS = 0.2 px (OpenCV's whole-number centres are 0.5
# px off) misses the square at that pixel
HALF, MISS = 0.3, 0.1
# depth is the pixel's ray met with the triangle's float32 plane (CONVENTIONS, "depth")
DEPTH_RTOL = 1e-6


def _scenes():
    return {"cage": load_scene(SCENES / "cage.toml").replace(**SIZE),
            "stack": load_scene(SCENES / "stack.toml").replace(**SIZE),
            "cards off-centre": off_centre(cards_scene(**SIZE))}


@pytest.mark.parametrize("name", sorted(_scenes()))
def test_written_matrices_read_back_give_the_same_file(tmp_path, name):
    scene = _scenes()[name]
    first = tmp_path / "first.toml"
    save_scene(scene, first)
    assert raytrace_main(["masks", str(first), "-o", str(tmp_path / "a.npz"), "--no-png",
                          "--outputs", "all"]) == 0
    a = dict(np.load(tmp_path / "a.npz"))
    camera = camera_from_matrices(a["K"], a["camera_to_world"], scene.camera.near)
    second = tmp_path / "second.json"
    save_scene(load_scene(first).replace(camera=camera), second)
    assert raytrace_main(["masks", str(second), "-o", str(tmp_path / "b.npz"), "--no-png",
                          "--outputs", "all"]) == 0
    b = dict(np.load(tmp_path / "b.npz"))
    assert sorted(a) == sorted(b)
    for key in a:
        assert a[key].dtype == b[key].dtype and np.array_equal(a[key], b[key], equal_nan=True), key
    assert a["lit"].any() and (a["coverage"][None] & ~a["lit"]).any()   # shadows to compare
    if scene.camera.matrix_form:   # written back exactly as given
        assert np.array_equal(a["camera_to_world"], scene.camera.camera_to_world)
        assert a["K"].tolist() == [[scene.camera.fx, 0, scene.camera.cx],
                                   [0, scene.camera.fy, scene.camera.cy], [0, 0, 1]]


def rotation(axis, degrees: float) -> np.ndarray:
    """(3, 3) float64 rotation about `axis` (Rodrigues)."""
    k = np.asarray(axis, np.float64) / np.linalg.norm(axis)
    a = np.radians(degrees)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(a) * kx + (1 - np.cos(a)) * kx @ kx


def project(K: np.ndarray, camera_to_world: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(n, 3) world points -> (n, 3) float64 (u, v, depth), plainly from the definitions: the
    OpenGL camera coordinates by solving with camera_to_world, flipped to OpenCV's, times K."""
    gl = np.linalg.solve(camera_to_world, np.c_[points, np.ones(len(points))].T).T[:, :3]
    cv = gl * [1.0, -1.0, -1.0]
    uvw = cv @ K.T
    return np.c_[uvw[:, :2] / uvw[:, 2:], cv[:, 2]]


def pixel_targets(seed: int, width: int = 64, height: int = 48, n: int = 8):
    """A scene of `n` small squares facing a turned camera with fx != fy and an off-centre
    principal point, each square centred near the centre of a known pixel, and the squares'
    centres (n, 3), the pixels (n, 2) (x, y) and the camera's K."""
    rng = np.random.default_rng(seed)
    m = np.eye(4)
    m[:3, :3] = rotation(rng.normal(size=3), rng.uniform(20, 160))
    m[:3, 3] = rng.uniform(-5, 5, 3)
    fx, fy = rng.uniform(50, 90), rng.uniform(50, 90)
    cx, cy = width * rng.uniform(0.2, 0.8), height * rng.uniform(0.2, 0.8)
    camera = Camera(fx=fx, fy=fy, cx=cx, cy=cy, camera_to_world=m)
    K = np.array([[fx, 0, cx], [0, fy, cy], [0, 0, 1.0]])
    pixels = np.stack([rng.choice(np.arange(2, width - 2), n, replace=False),
                       rng.choice(np.arange(2, height - 2), n, replace=False)], axis=1)
    uv = pixels + 0.5 + rng.uniform(-MISS, MISS, (n, 2))
    z = rng.uniform(2.0, 9.0, n)
    right, up = m[:3, 0], m[:3, 1]
    objects, centres = [], []
    for k in range(n):
        gl = np.array([(uv[k, 0] - cx) / fx * z[k], -(uv[k, 1] - cy) / fy * z[k], -z[k], 1.0])
        c = (m @ gl)[:3]
        hx, hy = HALF * z[k] / fx * right, HALF * z[k] / fy * up
        corners = [c - hx - hy, c + hx - hy, c + hx + hy, c - hx + hy]
        objects.append(Object(f"square{k}", corners, [[0, 1, 2], [0, 2, 3]]))
        centres.append(c)
    scene = Scene(camera=camera, objects=objects, lights=[DirectionalLight(-m[:3, 2])],
                  width=width, height=height)
    return scene, np.array(centres), pixels, K


def check_seen(K, camera_to_world, centres, pixels, object_id, depth, normal) -> None:
    """Each square k is seen at its pixel, at its depth, with its normal; unprojected, the
    pixel gives back a point of the square (within its half-size)."""
    uvz = project(K, camera_to_world, centres)
    np.testing.assert_array_equal(np.floor(uvz[:, :2]).astype(int), pixels)
    xs, ys = pixels[:, 0], pixels[:, 1]
    assert object_id[ys, xs].tolist() == list(range(1, len(pixels) + 1))
    np.testing.assert_allclose(depth[ys, xs], uvz[:, 2], rtol=DEPTH_RTOL)
    back = camera_to_world[:3, 2]
    np.testing.assert_allclose(np.abs(normal[ys, xs] @ back), 1.0, rtol=1e-6)
    points = unproject(K, camera_to_world, depth)[ys, xs]
    pixel_size = uvz[:, 2] / min(K[0, 0], K[1, 1])
    assert (np.linalg.norm(points - centres, axis=1) <= (HALF + MISS) * 1.5 * pixel_size).all()
    # and nothing else: a square is 0.6 px wide, so it covers at most 4 pixels
    assert 0 < (object_id > 0).sum() <= 4 * len(pixels)


@pytest.mark.parametrize("seed", range(6))
def test_points_projected_with_K_are_seen_at_their_pixel(seed):
    scene, centres, pixels, K = pixel_targets(seed)
    truth = raytrace.ground_truth(scene, outputs=("depth", "normal", "object_id"))
    np.testing.assert_array_equal(truth.calibration.K, K)
    np.testing.assert_array_equal(truth.calibration.camera_to_world,
                                  scene.camera.camera_to_world)
    check_seen(K, truth.calibration.camera_to_world, centres, pixels, truth.object_id,
               truth.depth, truth.normal)
