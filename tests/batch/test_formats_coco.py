"""`--format coco` decoded with pycocotools, pixel for pixel against the `object_id` and
`casters` outputs of the same frames; lights without casters (an area light) have no shadow
categories."""

from __future__ import annotations

import json

import numpy as np
import pytest
from builders import SCENES, job_lines, write_jobs

from shadowvol import batch
from shadowvol.batch.datasets.coco import SHADOW_IDS
from shadowvol.batch.datasets.encoding import rle

# pycocotools' own decode warns under numpy 2 (its __array__ has no copy keyword)
pytestmark = pytest.mark.filterwarnings("ignore:__array__ implementation:DeprecationWarning")

coco_api = pytest.importorskip("pycocotools.coco", reason="pip install 'shadowvol[coco]'")
mask_api = pytest.importorskip("pycocotools.mask", reason="pip install 'shadowvol[coco]'")


def _made(folder, lines):
    jobs = write_jobs(folder / "jobs.jsonl", lines)
    assert batch.run(jobs, folder / "coco", format="coco", progress=False).status == 0
    truth = write_jobs(folder / "truth.jsonl",
                       [dict(job, outputs=["object_id", "casters"]) for job in lines])
    assert batch.run(truth, folder / "files", progress=False).status == 0
    return folder / "coco", folder / "files"


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    return _made(tmp_path_factory.mktemp("coco"), job_lines(frames=2, size=(64, 48)))


def test_rle_is_pycocotools_encoding():
    rng = np.random.default_rng(28)
    masks = [np.zeros((1, 1), bool), np.ones((1, 1), bool), np.ones((5, 7), bool),
             np.zeros((4, 3), bool)]
    masks += [rng.random(tuple(rng.integers(1, 60, 2))) < rng.random() for _ in range(300)]
    for mask in masks:
        want = mask_api.encode(np.asfortranarray(mask.astype(np.uint8)))
        got = rle(mask)
        assert (got["counts"], got["size"]) == (want["counts"].decode(), want["size"])
        assert np.array_equal(mask_api.decode(got), mask)


@pytest.mark.gl
@pytest.mark.parametrize("job, lights, first", [("cage-turntable", 1, 0), ("cage-traced", 2, 2)])
def test_annotations_are_the_object_id_and_casters_outputs(made, job, lights, first):
    """The cage (object_id 4, class "cage", id 1) is annotated; the floor and walls are planes,
    the background, and are not.  One category table for both jobs (2 lights at most), image
    ids counted over the dataset (the second job's from 2)."""
    coco_out, files = made
    coco = coco_api.COCO(str(coco_out / job / "annotations.json"))
    names = [c["name"] for c in coco.loadCats(coco.getCatIds()) if c["supercategory"] == "object"]
    assert names == ["cage"]
    shadow_cats = {c["id"] for c in coco.cats.values() if c["supercategory"] == "shadow"}
    assert shadow_cats == {SHADOW_IDS * (i + 1) + 1 for i in range(2)}
    assert sorted(coco.getImgIds()) == [first, first + 1]
    for im in coco.getImgIds():
        ids = np.load(files / job / f"{im - first:06d}.object_id.npy")
        casters = np.load(files / job / f"{im - first:06d}.casters.npy")
        want = {1: ids == 4} if (ids == 4).any() else {}
        for i in range(lights):
            bit = (casters[i][..., 0] >> np.uint64(3)) & np.uint64(1) != 0
            if bit.any():
                want[SHADOW_IDS * (i + 1) + 1] = bit
        anns = coco.loadAnns(coco.getAnnIds(imgIds=[im]))
        assert sorted(a["category_id"] for a in anns) == sorted(want)
        for ann in anns:
            decoded = mask_api.decode(ann["segmentation"]).astype(bool)   # column-major RLE
            assert np.array_equal(decoded, want[ann["category_id"]]), ann["category_id"]
            assert np.array_equal(coco.annToMask(ann).astype(bool), decoded)
            assert ann["area"] == decoded.sum()
            assert list(mask_api.toBbox(ann["segmentation"])) == ann["bbox"]


@pytest.mark.gl
def test_an_area_light_has_shadow_categories(tmp_path):
    area = {"type": "rect", "center": [0.0, 2.5, 0.0],
            "normal": [0.0, -1.0, 0.0], "size": [0.4, 0.4], "samples": 4}
    lines = [{"name": "lamp", "scene": str(SCENES / "cage.toml"), "size": [32, 24],
              "lights": [area, {"type": "point", "position": [0.0, 1.4, 0.0]}],
              "cameras": [{"eye": [4.2, 3.4, 5.2], "target": [-0.6, 1.0, -0.8]}]}]
    jobs = write_jobs(tmp_path / "jobs.jsonl", lines)
    assert batch.run(jobs, tmp_path / "coco", format="coco", progress=False).status == 0
    data = json.loads((tmp_path / "coco" / "lamp" / "annotations.json").read_text())
    assert data["info"]["shadow_lights"] == [0, 1]   # the area light too
    shadow = {c["id"] // SHADOW_IDS - 1 for c in data["categories"]
              if c["supercategory"] == "shadow"}
    assert shadow == {0, 1}
    found = {a["category_id"] // SHADOW_IDS - 1 for a in data["annotations"]
             if a["category_id"] >= SHADOW_IDS}
    assert 0 in found   # the area light's cast shadows are annotated


@pytest.mark.gl
def test_a_scene_of_more_than_64_objects_has_their_shadows(tmp_path):
    from shadowvol.primitives import box, plane
    from shadowvol.scene import Camera, PointLight, Scene

    cubes = [box(f"cube {i}", center=(0.3 * (i % 13) - 1.8, 0.1, 0.3 * (i // 13) - 0.6),
                 size=(0.2, 0.2, 0.2)) for i in range(65)]
    scene = Scene(camera=Camera(eye=[0.0, 3.0, 4.0], target=[0.0, 0.0, 0.0]),
                  objects=(plane("floor"), *cubes),
                  lights=(PointLight(position=[0.0, 3.0, 0.0]),), width=32, height=24)
    job = {"name": "cubes", "scene": scene, "cameras": [{"eye": [0.0, 3.0, 4.0],
                                                         "target": [0.0, 0.0, 0.0]}]}
    summary = batch.run([job], tmp_path / "coco", format="coco", progress=False)
    assert summary.status == 0, summary.errors
    data = json.loads((tmp_path / "coco" / "cubes" / "annotations.json").read_text())
    assert data["info"]["shadow_lights"] == [0]
    assert {c["supercategory"] for c in data["categories"]} == {"object", "shadow"}
    objects = {a["category_id"] for a in data["annotations"] if a["category_id"] < SHADOW_IDS}
    shadows = {a["category_id"] - SHADOW_IDS for a in data["annotations"]
               if a["category_id"] >= SHADOW_IDS}
    assert len(objects) > 30
    assert max(shadows) > 64   # a cube of the second caster word casts
