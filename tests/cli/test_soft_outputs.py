"""`--outputs all` with an area light, in both commands (scenes/soft.toml: 144 samples): exit
0, and every array the docs name, with its dtype and shape; the two files agree.  Without
--outputs the mask file of an area light still holds lit_count and samples; a hard-light
scene's holds neither (its files are unchanged)."""

from __future__ import annotations

import numpy as np
import pytest
from builders import SCENES

from shadowvol.cli.main import main as shadowvol_main
from shadowvol.cli.raytrace import main as raytrace_main
from shadowvol.io import load_mask_arrays
from shadowvol.scenefile import load_scene, save_scene

H, W = 480, 640
# name -> dtype, shape of scenes/soft.toml's file (one light, 144 samples, 5 objects: K = 1)
WANT = {"lit": (np.bool_, (1, H, W)), "coverage": (np.bool_, (H, W)),
        "lit_count": (np.uint16, (1, H, W)), "samples": (np.int64, (1,)),
        "facing": (np.bool_, (1, H, W)), "facing_count": (np.uint16, (1, H, W)),
        "casters": (np.uint64, (1, H, W, 1)), "depth": (np.float32, (H, W)),
        "distance": (np.float32, (H, W)), "normal": (np.float32, (H, W, 3)),
        "object_id": (np.uint16, (H, W)), "light_samples_0": (np.float64, (144, 3))}


def check_file(arrays: dict) -> None:
    for name, (dtype, shape) in WANT.items():
        assert arrays[name].dtype == dtype and arrays[name].shape == shape, name
    assert arrays["samples"].tolist() == [144]
    np.testing.assert_array_equal(arrays["lit"], arrays["lit_count"] == 144)
    np.testing.assert_array_equal(arrays["facing"], arrays["facing_count"] > 0)
    np.testing.assert_array_equal(arrays["casters"].any(-1),
                                  arrays["lit_count"] < arrays["facing_count"])
    penumbra = (arrays["lit_count"] > 0) & (arrays["lit_count"] < 144)
    umbra = arrays["coverage"] & (arrays["facing_count"] > 0) & (arrays["lit_count"] == 0)
    assert penumbra.sum() > 1000 and umbra.sum() > 1000


@pytest.mark.gl
def test_outputs_all_with_an_area_light_in_both_commands(tmp_path):
    raster, traced = tmp_path / "r.npz", tmp_path / "t.npz"
    assert shadowvol_main(["render", str(SCENES / "soft.toml"), "-o", str(tmp_path / "s.png"),
                           "--masks", str(raster), "--outputs", "all"]) == 0
    assert raytrace_main(["masks", str(SCENES / "soft.toml"), "-o", str(traced), "--no-png",
                          "--outputs", "all"]) == 0
    a, b = load_mask_arrays(raster), load_mask_arrays(traced)
    assert set(a) == set(b)
    for arrays in (a, b):
        check_file(arrays)
    # the full budgets are tests/raster/test_groundtruth_vs_raytrace.py's; here: few differ
    for name in ("lit_count", "facing_count", "facing", "object_id"):
        assert (a[name] != b[name]).sum() <= 0.0005 * H * W, name
    assert (a["casters"] != b["casters"]).any(-1).sum() <= 0.0005 * H * W


@pytest.mark.gl
def test_an_area_light_mask_file_holds_its_counts_without_outputs(tmp_path):
    scene = load_scene(SCENES / "soft.toml").replace(width=64, height=48)
    save_scene(scene, tmp_path / "soft.json")
    hard = load_scene(SCENES / "stack.toml").replace(width=64, height=48)
    save_scene(hard, tmp_path / "hard.json")
    for name in ("soft", "hard"):
        src = str(tmp_path / f"{name}.json")
        assert shadowvol_main(["render", src, "-o", str(tmp_path / f"{name}.png"), "--masks",
                               str(tmp_path / f"{name}-r.npz")]) == 0
        assert raytrace_main(["masks", src, "-o", str(tmp_path / f"{name}-t.npz"),
                              "--no-png"]) == 0
    for who in ("r", "t"):
        soft = load_mask_arrays(tmp_path / f"soft-{who}.npz")
        assert soft["lit_count"].dtype == np.uint16 and soft["lit_count"].shape == (1, 48, 64)
        assert soft["samples"].tolist() == [144]
        np.testing.assert_array_equal(soft["lit"], soft["lit_count"] == 144)
        hard_file = load_mask_arrays(tmp_path / f"hard-{who}.npz")
        assert "lit_count" not in hard_file and "samples" not in hard_file
