"""A batch job with an area light writes every ground-truth array, and the mask file its
counts (lit_count, samples), in files and in webdataset shards (the same bytes), from both
renderers."""

from __future__ import annotations

import io

import numpy as np
import pytest
from builders import SCENES, output_files

from shadowvol import batch
from shadowvol.frame import GROUND_TRUTH

AREA = {"type": "disk", "center": [0.0, 3.0, 0.5], "normal": [0.0, -1.0, 0.0],
        "radius": 0.4, "samples": 9}
SHAPES = {"depth": ("float32", (30, 40)), "distance": ("float32", (30, 40)),
          "normal": ("float32", (30, 40, 3)), "object_id": ("uint16", (30, 40)),
          "facing": ("bool", (2, 30, 40)), "facing_count": ("uint16", (2, 30, 40)),
          "casters": ("uint64", (2, 30, 40, 1))}


def jobs() -> list[dict]:
    view = {"eye": [4.0, 3.0, 5.0], "target": [0.0, 1.0, 0.0]}
    return [{"name": name, "scene": str(SCENES / "stack.toml"), "size": [40, 30],
             "renderer": name, "cameras": [view], "outputs": ["masks", *GROUND_TRUTH],
             "lights": [AREA, {"type": "point", "position": [1.0, 4.0, 1.0]}]}
            for name in ("shadowvol", "raytrace")]


@pytest.mark.gl
def test_area_light_frames_hold_every_array_in_files_and_webdataset(tmp_path):
    assert set(SHAPES) == set(GROUND_TRUTH)
    assert batch.run(jobs(), tmp_path / "files", progress=False).status == 0
    assert batch.run(jobs(), tmp_path / "tars", format="webdataset", progress=False).status == 0
    files = output_files(tmp_path / "files")
    members = {}
    import tarfile
    for tar in sorted((tmp_path / "tars").glob("*.tar")):
        with tarfile.open(tar) as archive:
            members |= {m.name: archive.extractfile(m).read() for m in archive.getmembers()}
    frames = {}
    for job in ("shadowvol", "raytrace"):
        arrays = {name: np.load(io.BytesIO(files[f"{job}/000000.{name}.npy"]))
                  for name in GROUND_TRUTH}
        for name, (dtype, shape) in SHAPES.items():
            assert (str(arrays[name].dtype), arrays[name].shape) == (dtype, shape), (job, name)
        masks = np.load(io.BytesIO(files[f"{job}/000000.masks.npz"]))
        assert masks["samples"].tolist() == [9, 1]
        np.testing.assert_array_equal(masks["lit"], masks["lit_count"] == [[[9]], [[1]]])
        np.testing.assert_array_equal(arrays["casters"].any(-1),
                                      masks["lit_count"] < arrays["facing_count"])
        assert arrays["casters"][0].any() and arrays["facing_count"][0].max() == 9
        for suffix in ["masks.npz"] + [f"{name}.npy" for name in GROUND_TRUTH]:
            key = f"{job}/000000.{suffix}"
            assert members[key] == files[key], key   # the same bytes in the shard
        frames[job] = arrays, masks
    (ra, rm), (ta, tm) = frames["shadowvol"], frames["raytrace"]
    assert (rm["lit_count"] != tm["lit_count"]).sum() <= 12
    assert (ra["facing_count"] != ta["facing_count"]).sum() <= 12
