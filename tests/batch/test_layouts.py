"""The batch's design holds: layouts are frozen rows of one table, renderers rows of another,
frame specs typed and frozen with the spec hashes manifests already hold, and neither the
runner nor the worker tests a layout's or a renderer's name."""

from __future__ import annotations

import argparse
import ast
import dataclasses
import inspect

import pytest
from builders import ROOT

from shadowvol.batch import job_frames, layouts, sources
from shadowvol.batch.jobs import check_jobs
from shadowvol.batch.spec import FrameSpec
from shadowvol.batch.store import FileStore, Store, TarStore
from shadowvol.cli.batch import add_parser

JOBS = [{"name": "orbit", "scene": str(ROOT / "scenes" / "cage.toml"), "size": [40, 30],
         "cameras": {"orbit": {"center": [-0.6, 1.0, -0.8], "radius": 7.0, "elevation": 30.0,
                               "frames": 2}}, "outputs": ["image", "masks"]},
        {"name": "traced", "scene": str(ROOT / "scenes" / "cage.toml"), "renderer": "raytrace",
         "max_depth": 1, "seed": 7, "jitter": {"eye": 0.2},
         "lights": [{"type": "point", "position": [0.0, 1.4, 0.0]}],
         "cameras": [{"eye": [4.2, 3.4, 5.2], "target": [-0.6, 1.0, -0.8], "fov_y": 40.0}]}]

# job_frames.spec_hash(spec, "d") of these jobs' frames as the spec dicts before FrameSpec made them
# (and, last, of the first frame tagged "bop"): what the manifests of existing datasets hold
HASHES = {"orbit": ["063ba2055434db9bf697c73a2dd02cbf6516b51dcf8a26ef63eb3881d3364767",
                    "32cd9362d8461225c2317e88b7632741d48f4e79a6f6780e0e9fe26d8d9eb22b",
                    "f9d070358c35cba2d7c61c1a65f15a7c84e8ef7b0a946a988bebabcc1bc60eec"],
          "traced": ["52e9200cf032c0032b15ac0a7a1d4ec7057f4ca16a6fd4cce39173fec1ddb941",
                     "d1105f6c604584b3e5a295d6041ef8bf2dc69e2b8938ddb7128565ab4b61f90c"]}


def test_frame_specs_are_frozen_and_hash_as_before():
    for job in check_jobs(JOBS):
        specs = job_frames.specs(job, "key")
        assert all(isinstance(s, FrameSpec) for s in specs)
        tagged = layouts.tag(specs[:1], layouts.LAYOUTS["bop"])[0]
        got = [job_frames.spec_hash(s, "d") for s in specs] + [job_frames.spec_hash(tagged, "d")]
        assert got == HASHES[job.name]
        with pytest.raises(dataclasses.FrozenInstanceError):
            specs[0].renderer = "raytrace"
        assert layouts.tag(specs, layouts.LAYOUTS["webdataset"]) == specs   # plain: untagged


def test_layouts_are_frozen_rows_with_one_store_interface():
    assert tuple(layouts.LAYOUTS) == ("files", "webdataset", "nerfstudio", "bop", "coco", "istd",
                                      "soba", "soba-lights")
    parser = add_parser(argparse.ArgumentParser().add_subparsers())
    choices = next(a.choices for a in parser._actions if "--format" in a.option_strings)
    assert tuple(choices) == tuple(layouts.LAYOUTS)
    calls = [name for name in dir(Store) if not name.startswith("_") and name != "layout"]
    assert sorted(calls) == ["clean", "finish", "verify", "write"]
    for name, layout in layouts.LAYOUTS.items():
        assert dataclasses.is_dataclass(layout) and layout.name == name
        with pytest.raises(dataclasses.FrozenInstanceError):
            layout.shards = not layout.shards
        store = layout.make_store(ROOT)
        assert store.layout is layout
        for call in calls:   # the same signature in every store
            assert list(_parameters(getattr(type(store), call))) == \
                list(_parameters(getattr(Store, call))), (name, call)
    assert layouts.LAYOUTS["files"].store is FileStore
    assert layouts.LAYOUTS["webdataset"].store is TarStore
    assert set(sources.SOURCES) == {"shadowvol", "raytrace", "auto"}


def _parameters(function):
    return inspect.signature(function).parameters


@pytest.mark.parametrize("module", ["runner.py", "worker.py"])
def test_no_layout_or_renderer_name_is_tested(module):
    names = set(layouts.LAYOUTS) | set(sources.SOURCES)
    tree = ast.parse((ROOT / "shadowvol" / "batch" / module).read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            for side in [node.left, *node.comparators]:
                assert not (isinstance(side, ast.Constant) and side.value in names), \
                    f"{module}:{node.lineno} tests the name {side.value!r}"
        if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant):
            assert node.slice.value not in {"format", "renderer"}, \
                f"{module}:{node.lineno} reads [{node.slice.value!r}]"


def test_a_whole_dataset_layouts_frames_carry_their_jobs_place():
    """BOP's scene folder and COCO's ids are of the whole dataset: their specs carry the
    job's place (so their hashes differ from a dataset made before they had it, which is made
    again), nerfstudio's do not (its hashes stay)."""
    (job,) = check_jobs(JOBS[:1])
    specs = job_frames.specs(job, "key")
    for name in ("bop", "coco"):
        tagged = layouts.tag(specs, layouts.LAYOUTS[name], 3)
        assert [s.job_index for s in tagged] == [3, 3]
        assert tagged[0].as_dict()["job_index"] == 3
        assert job_frames.spec_hash(tagged[0], "d") != job_frames.spec_hash(
            layouts.tag(specs, layouts.LAYOUTS[name])[0], "d")
    nerf = layouts.tag(specs, layouts.LAYOUTS["nerfstudio"], 3)
    assert nerf[0].job_index is None and "job_index" not in nerf[0].as_dict()
