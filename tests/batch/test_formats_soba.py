"""`--format soba` and `soba-lights` read as SOBA's loader reads them (`pysobatools.soba.SOBA`
is pycocotools' COCO loading `annotations` and, beside it, `association_anno` under the
categories of `association`): every object mask is its `object_id` pixels, every shadow mask
its `casters` bit (merged over the lights, or per light), every association the union of its
pair; objects with no visible shadow, objects that cast none and background objects (category
"background") get none."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest
from builders import ROOT, job_lines, output_files, write_jobs

from shadowvol import batch
from shadowvol.primitives import box, plane
from shadowvol.scene import BACKGROUND, Camera, PointLight, Scene
from shadowvol.scenefile import load_scene

# pycocotools' own decode warns under numpy 2 (its __array__ has no copy keyword)
pytestmark = [pytest.mark.gl,
              pytest.mark.filterwarnings("ignore:__array__ implementation:DeprecationWarning")]

coco_api = pytest.importorskip("pycocotools.coco", reason="pip install 'shadowvol[coco]'")


class Soba:
    """What `pysobatools.soba.SOBA(annotation_file)` builds, from pycocotools' COCO:
    `instances` indexes `annotations` under `categories` (imgToAnns, catToImgs, annToMask),
    `associations` indexes `association_anno` under the association categories, which SOBA
    reads from `dataset['association']` (its getAssoIds fails without them)."""

    def __init__(self, path):
        self.dataset = json.loads(path.read_text())
        images = self.dataset["images"]
        self.instances = self._coco(images, self.dataset["categories"],
                                    self.dataset["annotations"])
        self.associations = self._coco(images, self.dataset["association"],
                                       self.dataset["association_anno"])

    @staticmethod
    def _coco(images, categories, annotations):
        coco = coco_api.COCO()
        coco.dataset = {"images": images, "categories": categories,
                        "annotations": annotations}
        coco.createIndex()
        return coco


def _casters_bit(casters: np.ndarray, j: int) -> np.ndarray:
    return (casters[..., j // 64] >> np.uint64(j % 64)) & np.uint64(1) != 0


def _check(path, truth, scene_objects, per_light: bool) -> int:
    """Check the file at `path` against the `object_id` and `casters` files under `truth`;
    the number of pairs."""
    soba = Soba(path)
    assert [c["name"] for c in soba.instances.loadCats([1, 2])] == ["Object", "Shadow"]
    assert soba.associations.getCatIds() == [1]
    pairs = 0
    for im in soba.instances.getImgIds():
        ids = np.load(truth / f"{im:06d}.object_id.npy")
        casters = np.load(truth / f"{im:06d}.casters.npy")
        want = {}
        for j, casts in enumerate(scene_objects):
            bits = _casters_bit(casters, j)
            shadows = {(i,): bits[i] for i in range(len(bits))} if per_light else \
                {tuple(i for i in range(len(bits)) if bits[i].any()): bits.any(0)}
            for lights, shadow in shadows.items():
                if casts and shadow.any() and (ids == j + 1).any():
                    want[(j + 1, lights)] = (ids == j + 1, shadow)
        anns = soba.instances.loadAnns(soba.instances.getAnnIds(imgIds=[im]))
        by_pair = {}
        for ann in anns:
            by_pair.setdefault(ann["association"], {})[ann["category_id"]] = ann
        assocs = soba.associations.loadAnns(soba.associations.getAnnIds(imgIds=[im]))
        assert sorted(a["association"] for a in assocs) == sorted(by_pair) == \
            list(range(1, len(want) + 1))
        got = {}
        for assoc in assocs:
            pair = by_pair[assoc["association"]]
            obj, shadow = pair[1], pair[2]
            assert sorted(pair) == [1, 2] and obj["object_id"] == shadow["object_id"]
            key = (obj["object_id"], tuple(shadow["light"]))
            assert tuple(assoc["light"]) == key[1] and assoc["category_id"] == 1
            seen, dark = (soba.instances.annToMask(a).astype(bool) for a in (obj, shadow))
            got[key] = (seen, dark)
            union = soba.associations.annToMask(assoc).astype(bool)
            assert np.array_equal(union, seen | dark), key
            for ann, mask in ((obj, seen), (shadow, dark), (assoc, union)):
                assert ann["area"] == mask.sum() and ann["iscrowd"] == 0
        assert sorted(got) == sorted(want), im
        for key, (seen, dark) in want.items():
            assert np.array_equal(got[key][0], seen), key
            assert np.array_equal(got[key][1], dark), key
        pairs += len(want)
    return pairs


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    folder = tmp_path_factory.mktemp("soba")
    lines = job_lines(frames=2, size=(48, 36))
    jobs = write_jobs(folder / "jobs.jsonl", lines)
    for name in ("soba", "soba-lights"):
        summary = batch.run(jobs, folder / name, format=name, progress=False)
        assert summary.status == 0, summary.errors
    truth = write_jobs(folder / "truth.jsonl",
                       [dict(job, outputs=["object_id", "casters"]) for job in lines])
    assert batch.run(truth, folder / "files", progress=False).status == 0
    return jobs, folder


@pytest.mark.parametrize("job", ["cage-turntable", "cage-traced"])
def test_shadows_are_the_casters_bits_merged_or_per_light(made, job):
    _, folder = made
    # the cage scene: floor, two walls (planes: the background by default), cage
    casts = [o.cast_shadows and o.label != BACKGROUND
             for o in load_scene(ROOT / "scenes" / "cage.toml").objects]
    assert casts.count(True) >= 1
    merged = _check(folder / "soba" / job / "annotations.json", folder / "files" / job, casts,
                    per_light=False)
    apart = _check(folder / "soba-lights" / job / "annotations.json", folder / "files" / job,
                   casts, per_light=True)
    assert merged >= 2 and apart >= merged
    if job == "cage-traced":   # two lights: the cage has a shadow from each
        assert apart > merged


def _pillar_scene(background_casts: bool, category: str | None = None) -> Scene:
    floor = replace(plane("floor", size=[8.0, 8.0]), cast_shadows=False)
    pillar = replace(box("pillar", center=(-1.0, 0.75, -1.0), size=(0.3, 1.5, 0.3)),
                     cast_shadows=background_casts, category=category)
    cube = box("cube", center=(1.0, 0.25, 0.0), size=(0.5, 0.5, 0.5))
    camera = Camera(eye=[0.0, 4.0, 5.0], target=[0.0, 0.0, 0.0])
    return Scene(camera=camera, objects=(floor, pillar, cube),
                 lights=(PointLight(position=[0.0, 3.0, 0.5]),), width=48, height=36)


@pytest.mark.parametrize("background_casts, category", [(True, None), (False, None),
                                                          (True, BACKGROUND)])
def test_background_objects_and_objects_without_a_visible_shadow_get_no_pair(
        tmp_path, background_casts, category):
    """The pillar casting, not casting, and casting but of category "background" (the stage:
    never an instance, its shadow not annotated)."""
    scene = _pillar_scene(background_casts, category)
    job = {"name": "pillar", "scene": scene, "cameras": [{"eye": [0.0, 4.0, 5.0],
                                                         "target": [0.0, 0.0, 0.0]}]}
    assert batch.run([job], tmp_path / "soba", format="soba", progress=False).status == 0
    truth = dict(job, outputs=["object_id", "casters"])
    assert batch.run([truth], tmp_path / "files", progress=False).status == 0
    casts = [obj.cast_shadows and obj.label != BACKGROUND for obj in scene.objects]
    pairs = _check(tmp_path / "soba" / "pillar" / "annotations.json",
                   tmp_path / "files" / "pillar", casts, per_light=False)
    data = json.loads((tmp_path / "soba" / "pillar" / "annotations.json").read_text())
    paired = {a["object_id"] for a in data["annotations"]}
    assert 1 not in paired   # the floor casts nothing
    pillar = background_casts and category is None
    assert (2 in paired) == pillar and 3 in paired
    assert pairs == 1 + pillar


def test_the_cli_writes_both_layouts_and_a_rerun_changes_nothing(made, tmp_path):
    jobs, folder = made
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    for name in ("soba", "soba-lights"):
        out = tmp_path / name
        for _ in range(2):
            done = subprocess.run([sys.executable, "-m", "shadowvol", "batch", str(jobs), "-o",
                                   str(out), "--format", name], env=env, capture_output=True,
                                  text=True)
            assert done.returncode == 0, done.stderr
            want, got = output_files(folder / name), output_files(out)
            assert sorted(got) == sorted(want)
            assert [k for k in want if got[k] != want[k]] == []


def _sobas_loader():
    """SOBA's own `pysobatools.soba.SOBA` (tests/batch/pysobatools_soba.py, vendored)."""
    import importlib.util
    from pathlib import Path

    spec = importlib.util.spec_from_file_location(
        "pysobatools_soba", Path(__file__).with_name("pysobatools_soba.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.SOBA


@pytest.mark.parametrize("layout", ["soba", "soba-lights"])
def test_sobas_own_loader_reads_what_the_checked_reader_reads(made, layout):
    """SOBA's own loader indexes the files as the reader `_check` verified against the casters
    bits: the same images, categories, association categories, annotations and association
    annotations per image, and the same mask for each (its annToMask)."""
    jobs, folder = made
    SOBA = _sobas_loader()
    for path in sorted((folder / layout).glob("*/annotations.json")):
        theirs, ours = SOBA(str(path)), Soba(path)
        assert theirs.getCatIds() == [1, 2] and theirs.getAssoIds() == [1]
        assert [c["name"] for c in theirs.loadAsso([1])] == ["Object-Shadow"]
        assert sorted(theirs.getImgIds()) == sorted(ours.instances.getImgIds())
        pairs = 0
        for im in theirs.getImgIds():
            anns = theirs.loadAnns(theirs.getAnnIds(imgIds=[im]))
            assert sorted(a["id"] for a in anns) == sorted(ours.instances.getAnnIds(imgIds=[im]))
            assocs = theirs.loadAssoAnns(theirs.getAssoAnnIds(imgIds=[im]))
            assert sorted(a["id"] for a in assocs) == \
                sorted(ours.associations.getAnnIds(imgIds=[im]))
            for ann in anns:
                assert np.array_equal(theirs.annToMask(ann), ours.instances.annToMask(ann))
            for assoc in assocs:
                members = [a for a in anns if a["association"] == assoc["association"]]
                assert sorted(a["category_id"] for a in members) == [1, 2]
                union = np.logical_or(*(theirs.annToMask(a) for a in members))
                assert np.array_equal(theirs.annToMask(assoc).astype(bool), union)
            pairs += len(assocs)
        assert pairs >= 1
