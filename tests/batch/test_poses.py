"""Two jobs with shared classes and one mesh file (`builders.pose_jobs`: crates given by a
matrix and by Euler angles, a ball, a box of class "crate", the second job's objects jittered)
make one COCO and one BOP dataset, read as their readers read them: pycocotools' `COCO` and
`annToMask` for COCO; for BOP a reader of bop_toolkit's conventions (models_info.json,
models/obj_*.ply, scene_camera.json's cam_K and depth_scale, scene_gt.json's obj_id and
cam_R_m2c, cam_t_m2c in mm), whose posed models project onto their masks."""

from __future__ import annotations

import json

import numpy as np
import pytest
from builders import output_files, pose_jobs, write_jobs
from PIL import Image

from shadowvol import batch
from shadowvol.batch.datasets.coco import SHADOW_IDS

pytestmark = [pytest.mark.gl,
              pytest.mark.filterwarnings("ignore:__array__ implementation:DeprecationWarning")]
coco_api = pytest.importorskip("pycocotools.coco", reason="pip install 'shadowvol[coco]'")

# the classes and models in the order they are first met: job A's crates, then its ball; the
# box of job B is a third model of class "crate"
CLASSES = {"crate": 1, "ball": 2}
LABELS = {"crates": ["background", "crate", "crate", "ball"],
          "tossed": ["background", "ball", "crate", "crate"]}
MODELS = {"crates": [1, 1, 2], "tossed": [2, 3, 1]}   # obj_id of each non-background object
FOLDER = {"crates": "train/000000", "tossed": "train/000001"}
IN_MASK = 0.99   # of the visible model vertices that project into their dilated mask_visib
HIDDEN_MM = 30.0   # a vertex is hidden when the depth at its pixel is nearer by more than this


def _read(path) -> np.ndarray:
    with Image.open(path) as image:
        return np.asarray(image)


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    folder = tmp_path_factory.mktemp("poses")
    lines = pose_jobs(folder)
    for fmt in ("bop", "coco"):
        summary = batch.run(write_jobs(folder / "jobs.jsonl", lines), folder / fmt, format=fmt,
                            progress=False)
        assert summary.status == 0, summary.errors
    truth = write_jobs(folder / "truth.jsonl",
                       [dict(job, outputs=["object_id", "depth"]) for job in lines])
    assert batch.run(truth, folder / "files", progress=False).status == 0
    return folder


def test_coco_categories_and_ids_are_the_datasets(made):
    merged = coco_api.COCO(str(made / "coco" / "annotations.json"))
    objects = {c["name"]: c["id"] for c in merged.cats.values()
               if c["supercategory"] == "object"}
    assert objects == CLASSES
    assert {c["id"] for c in merged.cats.values() if c["supercategory"] == "shadow"} == \
        {SHADOW_IDS + c for c in CLASSES.values()}
    assert sorted(merged.getImgIds()) == [0, 1, 2, 3]
    ann_ids = [a["id"] for a in merged.dataset["annotations"]]
    assert sorted(ann_ids) == list(range(1, len(ann_ids) + 1))
    together = []
    for job in LABELS:   # each job's own file: the same table, its part of the ids
        own = json.loads((made / "coco" / job / "annotations.json").read_text())
        assert own["categories"] == merged.dataset["categories"]
        together += own["annotations"]
    assert together == merged.dataset["annotations"]


@pytest.mark.parametrize("job, first", [("crates", 0), ("tossed", 2)])
def test_coco_masks_are_each_objects_pixels_and_the_floor_is_not_annotated(made, job, first):
    merged = coco_api.COCO(str(made / "coco" / "annotations.json"))
    labels = LABELS[job]
    for frame in range(2):
        image = merged.imgs[first + frame]
        assert image["file_name"] == f"{job}/images/{frame:06d}.png"
        ids = np.load(made / "files" / job / f"{frame:06d}.object_id.npy")
        anns = [a for a in merged.loadAnns(merged.getAnnIds(imgIds=[first + frame]))
                if a["category_id"] < SHADOW_IDS]
        got = sorted((a["category_id"], merged.annToMask(a).astype(bool).tobytes())
                     for a in anns)
        want = sorted((CLASSES[labels[k - 1]], (ids == k).tobytes())
                      for k in range(2, len(labels) + 1) if (ids == k).any())
        assert got == want
        assert (ids == 1).any() and len(anns) == len(want)   # the floor is seen, not annotated


def _bop(made):
    root = made / "bop"
    info = json.loads((root / "models" / "models_info.json").read_text())
    models = {}
    for obj_id in info:
        lines = (root / "models" / f"obj_{int(obj_id):06d}.ply").read_text().splitlines()
        n = int(next(x for x in lines if x.startswith("element vertex")).split()[-1])
        start = lines.index("end_header") + 1
        models[int(obj_id)] = np.array([[float(x) for x in line.split()]
                                        for line in lines[start:start + n]])
    return root, info, models


def test_bop_models_are_one_per_mesh_in_its_own_frame(made):
    root, info, models = _bop(made)
    assert sorted(models) == [1, 2, 3]
    crate = np.array([[float(x) for x in line.split()[1:]]
                      for line in (made / "crate.obj").read_text().splitlines()
                      if line.startswith("v ")])
    assert np.allclose(models[1], crate * 1000, rtol=0, atol=1e-9)   # the file's frame, mm
    for obj_id, model in models.items():
        assert info[str(obj_id)]["size_x"] == pytest.approx(np.ptp(model[:, 0]))
        assert info[str(obj_id)]["diameter"] >= np.ptp(model, axis=0).max()


@pytest.mark.parametrize("job", list(FOLDER))
def test_bop_posed_models_project_onto_their_masks(made, job):
    root, _, models = _bop(made)
    scene = root / FOLDER[job]
    cameras = json.loads((scene / "scene_camera.json").read_text())
    gt = json.loads((scene / "scene_gt.json").read_text())
    assert sorted(gt) == ["0", "1"]
    for im, poses in gt.items():
        assert [p["obj_id"] for p in poses] == MODELS[job]
        K = np.array(cameras[im]["cam_K"]).reshape(3, 3)
        depth = _read(scene / "depth" / f"{int(im):06d}.png") * cameras[im]["depth_scale"]
        checked = 0
        for g, pose in enumerate(poses):
            R = np.array(pose["cam_R_m2c"]).reshape(3, 3)
            assert np.allclose(R.T @ R, np.eye(3), atol=1e-9) and np.linalg.det(R) > 0
            points = models[pose["obj_id"]] @ R.T + np.array(pose["cam_t_m2c"])
            uv = points @ K.T
            u, v = np.rint(uv[:, 0] / uv[:, 2]).astype(int), np.rint(uv[:, 1] / uv[:, 2]).astype(int)
            inside = (u >= 0) & (u < depth.shape[1]) & (v >= 0) & (v < depth.shape[0])
            u, v, z = u[inside], v[inside], points[inside, 2]
            # not hidden: nothing seen at its pixel lies nearer than it (beyond the change of
            # depth over a pixel at these sizes)
            seen = (depth[v, u] == 0) | (depth[v, u] > z - HIDDEN_MM)
            mask = _read(scene / "mask_visib" / f"{int(im):06d}_{g:06d}.png") == 255
            grown = mask.copy()   # dilated by 1 px (8-neighbourhood)
            for dy in (-1, 0, 1):
                for dx in (-1, 0, 1):
                    grown |= np.roll(np.roll(mask, dy, 0), dx, 1)
            if seen.sum():
                assert grown[v[seen], u[seen]].mean() >= IN_MASK, (job, im, g)
                checked += int(seen.sum())
        assert checked > 50, checked   # vertices were seen: the check ran


def test_bop_poses_are_the_jittered_ones_of_the_manifest(made):
    """cam_R_m2c, cam_t_m2c of the jittered job are the manifest's jittered object poses seen
    from the frame's camera, and the jitter turned them away from the scene's."""
    root = made / "bop"
    records = {r["id"]: r for r in map(json.loads,
                                        (root / "manifest.jsonl").read_text().splitlines())}
    cameras = json.loads((root / FOLDER["tossed"] / "scene_camera.json").read_text())
    gt = json.loads((root / FOLDER["tossed"] / "scene_gt.json").read_text())
    turned = 0
    for im in ("0", "1"):
        objects = records[f"tossed/{int(im):06d}"]["objects"]
        assert [o["category"] for o in objects] == LABELS["tossed"]
        R_w2c = np.array(cameras[im]["cam_R_w2c"]).reshape(3, 3)
        t_w2c = np.array(cameras[im]["cam_t_w2c"])
        for pose, obj in zip(gt[im], objects[1:]):
            m2w = np.array(obj["pose"])
            assert np.allclose(np.array(pose["cam_R_m2c"]).reshape(3, 3), R_w2c @ m2w[:3, :3],
                               atol=1e-9)
            assert np.allclose(pose["cam_t_m2c"], R_w2c @ m2w[:3, 3] * 1000 + t_w2c, atol=1e-6)
        tilted = np.array(objects[3]["pose"])[:3, :3]
        given = np.array(json.loads((made / "poses_b.toml").read_text().split(
            "matrix = ")[-1].rstrip().rstrip("}")))[:3, :3]
        turned += not np.allclose(tilted, given, atol=1e-6)
    assert turned == 2


def test_two_shards_or_two_workers_make_the_datasets_of_one_run(made):
    """Ids, models and the jittered poses do not depend on which shard or process made a
    frame."""
    for fmt in ("bop", "coco"):
        out = made / f"sharded-{fmt}"
        for shard in ("0/2", "1/2"):
            summary = batch.run(made / "jobs.jsonl", out, format=fmt, shard=shard,
                                progress=False)
            assert summary.status == 0, summary.errors
        pooled = made / f"pooled-{fmt}"
        assert batch.run(made / "jobs.jsonl", pooled, format=fmt, workers=2,
                         progress=False).status == 0
        want = output_files(made / fmt)
        for got in (output_files(out), output_files(pooled)):
            assert sorted(got) == sorted(want)
            assert [k for k in want if got[k] != want[k]] == []


def test_bop_refuses_a_scale_jitter_naming_it(tmp_path):
    job = dict(pose_jobs(tmp_path)[1], size=[16, 12], cameras=[{"eye": [0.5, 2.4, 4.2],
                                                                 "target": [0.0, 0.3, 0.0]}],
               jitter={"objects": {"scale": 0.2}})
    summary = batch.run([job], tmp_path / "bop", format="bop", progress=False)
    assert summary.status == 2 and len(summary.errors) == 1
    assert "jitter.objects.scale: object 'ball' is scaled by" in summary.errors[0]
    assert "\n" not in summary.errors[0]
    # the same frame in COCO has no pose to write: made
    assert batch.run([job], tmp_path / "coco", format="coco", progress=False).status == 0
