"""`--format nerfstudio` read back as nerfstudio reads it: each frame's 16-bit depth,
unprojected with the frame's intrinsics and transform_matrix (OpenGL camera axes), lands on the
triangles of the object its id PNG names, and reprojected into another frame meets that
frame's depth."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image
from builders import SCENES, job_lines, write_jobs

from shadowvol import batch
from shadowvol.scenefile import load_scene

pytestmark = pytest.mark.gl


def _read(path) -> np.ndarray:
    """A PNG's pixels as stored (Pillow opens a 16-bit grey PNG as mode I;16: uint16)."""
    with Image.open(path) as image:
        return np.asarray(image)

# the depth PNG holds whole millimetres: a point is off its triangle by at most half of one
# along the pixel's ray (which is longer than the depth by at most 1/cos of the half-diagonal
# field of view), plus float32 rendering
ON_SURFACE = 1e-3
# a reprojected point meets the other frame's depth where nothing hides it: at the frame's
# resolution the depth at a pixel's centre differs from the point's by the surface's slope
# across a pixel
AGREE = 0.02


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    folder = tmp_path_factory.mktemp("nerfstudio")
    jobs = write_jobs(folder / "jobs.jsonl", job_lines(frames=3, size=(64, 48)))
    summary = batch.run(jobs, folder / "out", format="nerfstudio", progress=False)
    assert summary.status == 0, summary.errors
    return folder / "out"


def _frames(root):
    transforms = json.loads((root / "transforms.json").read_text())
    assert transforms["camera_model"] == "OPENCV"
    for frame in transforms["frames"]:
        cam = {k: frame.get(k, transforms[k]) for k in ("fl_x", "fl_y", "cx", "cy", "w", "h")}
        depth = _read(root / frame["depth_file_path"])
        ids = _read(root / frame["object_id_path"])
        mask = _read(root / frame["mask_path"])
        assert depth.dtype == np.uint16 and ids.dtype == np.uint16 and mask.dtype == np.uint8
        assert depth.shape == (cam["h"], cam["w"])
        yield (cam, np.array(frame["transform_matrix"]),
               depth * transforms["depth_unit_scale_factor"], ids, mask)


def _unproject(cam, c2w, depth):
    """(H, W, 3) world points of the pixel centres, nerfstudio's way (pixel centres at +0.5,
    camera looking down -z, y up)."""
    v, u = np.mgrid[:cam["h"], :cam["w"]] + 0.5
    x = (u - cam["cx"]) / cam["fl_x"] * depth
    y = (v - cam["cy"]) / cam["fl_y"] * depth
    gl = np.stack([x, -y, -depth], axis=-1)
    return gl @ c2w[:3, :3].T + c2w[:3, 3]


def _distance_to_triangles(points, tris):
    """(n,) distance of each point to the plane of the nearest triangle that contains its
    projection (inf when none does): a point on the surface has one at distance ~0."""
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    rel = points[:, None, :] - a[None]
    dist = np.einsum("ptk,tk->pt", rel, n)
    foot = rel - dist[..., None] * n[None]
    e1, e2 = b - a, c - a
    d11, d12, d22 = (e1 * e1).sum(1), (e1 * e2).sum(1), (e2 * e2).sum(1)
    f1, f2 = np.einsum("ptk,tk->pt", foot, e1), np.einsum("ptk,tk->pt", foot, e2)
    den = d11 * d22 - d12 ** 2
    s, t = (d22 * f1 - d12 * f2) / den, (d11 * f2 - d12 * f1) / den
    inside = (s >= -1e-6) & (t >= -1e-6) & (s + t <= 1 + 1e-6)
    return np.where(inside, np.abs(dist), np.inf).min(axis=1)


@pytest.mark.parametrize("job", ["cage-turntable", "cage-traced"])
def test_depth_unprojects_onto_the_named_objects_triangles(dataset, job):
    scene = load_scene(SCENES / "cage.toml")
    frames = list(_frames(dataset / job))
    assert len(frames) == {"cage-turntable": 3, "cage-traced": 2}[job]
    for cam, c2w, depth, ids, mask in frames:
        assert np.array_equal(mask == 255, depth > 0) and np.array_equal(ids > 0, depth > 0)
        points = _unproject(cam, c2w, depth)
        for k, obj in enumerate(scene.objects, start=1):
            seen = ids == k
            if not seen.any():
                continue
            tris = np.asarray(obj.vertices, np.float64)[np.asarray(obj.faces)]
            far = _distance_to_triangles(points[seen], tris)
            assert far.max() < ON_SURFACE, (obj.name, float(far.max()))


def test_points_reproject_into_another_frame(dataset):
    (cam0, c2w0, depth0, _, _), (cam1, c2w1, depth1, _, _) = list(
        _frames(dataset / "cage-turntable"))[:2]
    points = _unproject(cam0, c2w0, depth0)[depth0 > 0]
    w2c = np.linalg.inv(c2w1)
    gl = points @ w2c[:3, :3].T + w2c[:3, 3]
    z = -gl[:, 2]
    u = gl[:, 0] / z * cam1["fl_x"] + cam1["cx"]
    v = -gl[:, 1] / z * cam1["fl_y"] + cam1["cy"]
    inside = (z > 0) & (u >= 0) & (u < cam1["w"]) & (v >= 0) & (v < cam1["h"])
    rows, cols = v[inside].astype(int), u[inside].astype(int)
    seen, z = depth1[rows, cols], z[inside]
    assert inside.sum() > 0.5 * len(points)
    # away from frame 1's depth edges (a pixel either side), where the point may project just
    # across an edge from the pixel centre that sees past it
    near = np.lib.stride_tricks.sliding_window_view(np.pad(depth1, 1, mode="edge"), (3, 3))
    low, high = near.min(axis=(2, 3)), near.max(axis=(2, 3))
    smooth = ((low > 0) & (high - low < AGREE * low))[rows, cols]
    close = np.abs(seen - z) < AGREE * z
    assert close[smooth].mean() > 0.9, float(close[smooth].mean())
    # nothing is seen behind a point there, which would be in front of it: only in front
    # (the point hidden in frame 1) or on it
    assert not (seen > z * (1 + AGREE))[smooth].any()


def test_the_16_bit_pngs_read_back_as_the_docs_say(dataset):
    """docs/formats.md: imageio.v3 (its pillow plugin) keeps uint16, as Pillow's asarray does."""
    iio = pytest.importorskip("imageio.v3", reason="imageio is the reader the docs name")
    path = dataset / "cage-turntable" / "depth" / "000000.png"
    got = iio.imread(path)
    assert got.dtype == np.uint16 and np.array_equal(got, _read(path)) and got.max() > 255
