"""`--format bop` against the BOP format's definitions (bop_toolkit docs/bop_datasets_format.md):
mask_visib is the object_id output, mask is the object drawn alone and holds it,
scene_gt_info counts those masks, and each model posed by cam_R_m2c, cam_t_m2c carries the
points the depth PNG (times depth_scale, mm) unprojects to with cam_K.  Both jobs are one
dataset, a scene folder each; the floor and walls (planes: the background) are no model."""

from __future__ import annotations

import json

import numpy as np
import pytest
from builders import SCENES, job_lines, write_jobs
from PIL import Image

from shadowvol import batch

pytestmark = pytest.mark.gl

# the depth PNG holds whole millimetres (depth_scale 1): a point is off its model's surface by
# at most half of one along the pixel's ray, plus float32 rendering
ON_SURFACE_MM = 1.0
JOBS = {"cage-turntable": 2, "cage-traced": 2}
FOLDER = {"cage-turntable": "000000", "cage-traced": "000001"}   # the jobs' places


def _read(path) -> np.ndarray:
    with Image.open(path) as image:
        return np.asarray(image)


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """The BOP dataset, and the same frames' object_id and depth from `--format files`."""
    folder = tmp_path_factory.mktemp("bop")
    lines = job_lines(frames=2, size=(64, 48))
    jobs = write_jobs(folder / "jobs.jsonl", lines)
    assert batch.run(jobs, folder / "bop", format="bop", progress=False).status == 0
    truth = write_jobs(folder / "truth.jsonl",
                       [dict(job, outputs=["object_id", "depth"]) for job in lines])
    assert batch.run(truth, folder / "files", progress=False).status == 0
    return folder / "bop", folder / "files"


def _ply(path) -> tuple[np.ndarray, np.ndarray]:
    lines = path.read_text().splitlines()
    n = int(next(x for x in lines if x.startswith("element vertex")).split()[-1])
    start = lines.index("end_header") + 1
    vertices = np.array([[float(x) for x in line.split()] for line in lines[start:start + n]])
    faces = np.array([[int(x) for x in line.split()[1:]] for line in lines[start + n:]])
    return vertices, faces


def _on_triangles(points, tris):
    """(n,) distance of each point to the plane of the nearest triangle that contains its
    projection (inf when none does)."""
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


@pytest.mark.parametrize("job", JOBS)
def test_masks_are_the_object_id_output_and_the_objects_drawn_alone(made, job):
    bop, files = made
    scene = bop / "train" / FOLDER[job]
    gt = json.loads((scene / "scene_gt.json").read_text())
    info = json.loads((scene / "scene_gt_info.json").read_text())
    assert list(gt) == [str(i) for i in range(JOBS[job])] == list(info)
    for im in range(JOBS[job]):
        ids = np.load(files / job / f"{im:06d}.object_id.npy")
        assert [pose["obj_id"] for pose in gt[str(im)]] == [1]   # the cage, the one model
        assert (ids == 4).any()
        for g, (pose, stats) in enumerate(zip(gt[str(im)], info[str(im)])):
            visib = _read(scene / "mask_visib" / f"{im:06d}_{g:06d}.png") == 255
            full = _read(scene / "mask" / f"{im:06d}_{g:06d}.png") == 255
            assert np.array_equal(visib, ids == 4)   # the cage's object_id
            assert not (visib & ~full).any()   # what is seen of it is part of it alone
            assert (stats["px_count_visib"], stats["px_count_all"]) == (visib.sum(), full.sum())
            if full.any():
                assert stats["visib_fract"] == pytest.approx(visib.sum() / full.sum())
                ys, xs = np.nonzero(full)
                assert stats["bbox_obj"] == [xs.min(), ys.min(), np.ptp(xs) + 1,
                                                 np.ptp(ys) + 1]


@pytest.mark.parametrize("job", JOBS)
def test_posed_models_carry_the_depth(made, job):
    bop, files = made
    scene = bop / "train" / FOLDER[job]
    cameras = json.loads((scene / "scene_camera.json").read_text())
    gt = json.loads((scene / "scene_gt.json").read_text())
    for im in range(JOBS[job]):
        cam = cameras[str(im)]
        K = np.array(cam["cam_K"]).reshape(3, 3)
        depth = _read(scene / "depth" / f"{im:06d}.png").astype(np.float64) * cam["depth_scale"]
        truth = np.load(files / job / f"{im:06d}.depth.npy")
        assert np.array_equal(depth > 0, np.isfinite(truth))
        assert np.abs(depth - truth * 1000)[depth > 0].max() <= 0.5 + 1e-3
        v, u = np.mgrid[:depth.shape[0], :depth.shape[1]]   # OpenCV: centres on whole numbers
        points = np.stack([(u - K[0, 2]) / K[0, 0] * depth, (v - K[1, 2]) / K[1, 1] * depth,
                           depth], axis=-1)
        for g, pose in enumerate(gt[str(im)]):
            visib = _read(scene / "mask_visib" / f"{im:06d}_{g:06d}.png") == 255
            if not visib.any():
                continue
            model, faces = _ply(bop / "models" / f"obj_{pose['obj_id']:06d}.ply")
            R = np.array(pose["cam_R_m2c"]).reshape(3, 3)
            posed = model @ R.T + np.array(pose["cam_t_m2c"])
            far = _on_triangles(points[visib], posed[faces])
            assert far.max() < ON_SURFACE_MM, (pose["obj_id"], float(far.max()))


def test_camera_and_models_info(made):
    """The cage's model is its mesh file in the file's own frame at the scene's scale (1.4), in
    mm; its pose turns it by the scene's 20 degrees about y, which BOP's cam_R_m2c carries."""
    import trimesh

    bop, _ = made
    info = json.loads((bop / "models" / "models_info.json").read_text())
    assert list(info) == ["1"] and sorted(p.name for p in (bop / "models").iterdir()) == \
        ["models_info.json", "obj_000001.ply"]
    model, faces = _ply(bop / "models" / "obj_000001.ply")
    mesh = trimesh.load(str(SCENES / "meshes" / "cage.obj"), process=False)
    assert np.allclose(model, np.asarray(mesh.vertices) * 1.4 * 1000, rtol=0, atol=1e-9)
    assert np.array_equal(faces, np.asarray(mesh.faces))
    assert info["1"]["size_x"] == pytest.approx(np.ptp(model[:, 0]))
    camera = json.loads((bop / "camera.json").read_text())
    assert (camera["width"], camera["height"]) == (64, 48) and camera["cx"] == 31.5
    for folder in FOLDER.values():
        scene = bop / "train" / folder
        cameras = json.loads((scene / "scene_camera.json").read_text())
        gt = json.loads((scene / "scene_gt.json").read_text())
        for im, poses in gt.items():
            w2c = np.array(cameras[im]["cam_R_w2c"]).reshape(3, 3)
            m2w = w2c.T @ np.array(poses[0]["cam_R_m2c"]).reshape(3, 3)   # model to world
            a = np.radians(20.0)
            turn = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
            assert np.allclose(m2w, turn, atol=1e-9)
