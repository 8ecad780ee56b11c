"""`raytrace masks --outputs` and `raytrace render --exr/--png16`: the NPZ holds what was asked
for plus the camera matrices and light arrays always, equal to the API's; bad lists exit 2."""

from __future__ import annotations

import numpy as np
import OpenEXR
import pytest
from builders import SCENES

import raytrace
from raytrace.groundtruth import ground_truth
from shadowvol.cli.raytrace import main
from shadowvol.io import load_mask_arrays
from shadowvol.scenefile import load_scene

CALIBRATION = {"K", "world_to_camera", "camera_to_world", "light_position", "light_direction"}
# stack.toml's lights: a point light (its position is its one sample) and a directional light
SAMPLES = {"light_samples_0"}


@pytest.fixture
def small(tmp_path):
    text = (SCENES / "stack.toml").read_text().replace("width = 640", "width = 64") \
        .replace("height = 480", "height = 48")
    path = tmp_path / "stack.toml"
    path.write_text(text)
    return path


def test_masks_with_outputs_holds_them_and_the_camera(small, tmp_path):
    out = tmp_path / "truth.npz"
    assert main(["masks", str(small), "-o", str(out), "--outputs", "casters,depth,object_id",
                 "--no-png"]) == 0
    arrays = load_mask_arrays(out)
    assert set(arrays) == {"lit", "coverage", "depth", "object_id", "casters"} | CALIBRATION \
        | SAMPLES
    truth = ground_truth(load_scene(small))
    for name in ("lit", "coverage", "depth", "object_id", "casters"):
        np.testing.assert_array_equal(arrays[name], getattr(truth, name))
    for name, value in truth.calibration.arrays().items():
        np.testing.assert_array_equal(arrays[name], value)


def test_masks_without_outputs_still_holds_the_camera(small, tmp_path):
    out = tmp_path / "m.npz"
    assert main(["masks", str(small), "-o", str(out), "--no-png"]) == 0
    assert set(load_mask_arrays(out)) == {"lit", "coverage"} | CALIBRATION | SAMPLES
    assert main(["masks", str(small), "-o", str(tmp_path / "all.npz"), "--no-png",
                 "--outputs", "all"]) == 0
    assert {"depth", "distance", "normal", "object_id", "facing", "casters"} <= \
        set(load_mask_arrays(tmp_path / "all.npz"))


@pytest.mark.parametrize("bad", ["depth,colour", "", ","])
def test_a_bad_output_list_exits_2_in_one_line(small, tmp_path, capsys, bad):
    assert main(["masks", str(small), "-o", str(tmp_path / "m.npz"), "--outputs", bad]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: --outputs: unknown output") and "\n" not in err
    assert not (tmp_path / "m.npz").exists()


def test_render_writes_exr_and_png16(small, tmp_path):
    png, exr, png16 = tmp_path / "a.png", tmp_path / "a.exr", tmp_path / "a16.png"
    assert main(["render", str(small), "-o", str(png), "--exr", str(exr), "--png16",
                 str(png16), "--max-depth", "0", "--no-progress"]) == 0
    image = raytrace.render(load_scene(small), max_depth=0, progress=False)
    with OpenEXR.File(str(exr)) as f:
        np.testing.assert_array_equal(f.channels()["RGB"].pixels, image.astype(np.float32))
    assert png16.read_bytes()[24] == 16  # the IHDR bit depth
    assert main(["render", str(small), "-o", str(png), "--exr", str(tmp_path / "a.png")]) == 2


@pytest.mark.gl
def test_shadowvol_render_masks_hold_the_camera_and_the_image_goes_to_exr(ctx, small,
                                                                          tmp_path):
    from shadowvol.cli.main import main as shadowvol_main

    png = tmp_path / "s.png"
    assert shadowvol_main(["render", str(small), "-o", str(png), "--masks", "--exr",
                           "--png16"]) == 0
    arrays = load_mask_arrays(tmp_path / "s-masks.npz")
    assert set(arrays) == {"lit", "coverage"} | CALIBRATION | SAMPLES
    truth = ground_truth(load_scene(small), ())
    for name, value in truth.calibration.arrays().items():
        np.testing.assert_array_equal(arrays[name], value)
    with OpenEXR.File(str(tmp_path / "s.exr")) as f:
        assert f.channels()["RGB"].pixels.shape == (48, 64, 3)
    assert (tmp_path / "s-16bit.png").read_bytes()[24] == 16


def test_the_datasets_ground_truth_example_runs_from_any_folder(tmp_path):
    """docs/datasets.md's ground-truth example, as written, in a fresh process in an empty folder
    (at a small image size): three views, each its EXR, 16-bit PNG, NPZ and picture."""
    import re
    import subprocess
    import sys

    from builders import ROOT

    blocks = re.findall(r"```python\n(.*?)```", (ROOT / "docs" / "datasets.md").read_text(),
                        flags=re.S)
    block = next(b for b in blocks if "ground_truth" in b)
    line = 'shadowvol.load_scene(shadowvol.example_scene("stack"))'
    assert line in block
    code = block.replace(line, line + ".replace(width=40, height=30)")
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == sorted(f"view{k}{s}" for k in range(3)
                           for s in (".exr", ".png", ".npz", "-truth.png"))
    arrays = load_mask_arrays(tmp_path / "view1.npz")
    assert {"depth", "distance", "normal", "object_id", "facing", "casters"} | CALIBRATION \
        <= set(arrays)
    first, second = load_mask_arrays(tmp_path / "view0.npz"), arrays
    assert not np.array_equal(first["world_to_camera"], second["world_to_camera"])


@pytest.mark.gl
def test_shadowvol_render_outputs_go_into_the_mask_file(ctx, small, tmp_path, capsys):
    from shadowvol.cli.main import main as shadowvol_main
    from shadowvol.raster.renderer import Renderer

    png = tmp_path / "s.png"
    assert shadowvol_main(["render", str(small), "-o", str(png), "--outputs",
                           "casters,normal"]) == 0
    arrays = load_mask_arrays(tmp_path / "s-masks.npz")
    assert set(arrays) == {"lit", "coverage", "normal", "casters"} | CALIBRATION | SAMPLES
    with Renderer(load_scene(small), ctx) as r:
        frame = r.render(outputs=("lit", "coverage", "normal", "casters"))
    for name in ("lit", "coverage", "normal", "casters"):
        np.testing.assert_array_equal(arrays[name], getattr(frame, name))
    assert shadowvol_main(["render", str(small), "-o", str(png), "--outputs", "depth,x"]) == 2
    assert "unknown output 'x'" in capsys.readouterr().err
