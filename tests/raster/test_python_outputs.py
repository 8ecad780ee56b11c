"""In Python as on the command line: `shadowvol.render(scene, outputs=...)` adds to the default
image, lit and coverage (it once replaced them, and the next save_masks failed with "got
object() and object()"); `save_masks(path, frame)` writes a frame whole, with its camera
matrices; a frame rendered without its masks is refused naming what it lacks."""

from __future__ import annotations

import numpy as np
import pytest
from builders import SCENES

import raytrace
import shadowvol
from shadowvol.frame import save_masks
from shadowvol.raster.renderer import Renderer
from shadowvol.scenefile import load_scene


@pytest.fixture
def scene():
    return load_scene(SCENES / "cage.toml").replace(width=48, height=36)


def test_outputs_add_to_the_defaults(scene, ctx):
    frame = shadowvol.render(scene, outputs=("depth",), ctx=ctx)
    assert frame.image is not None and frame.lit is not None and frame.coverage is not None
    assert frame.depth.shape == (36, 48)
    plain = shadowvol.render(scene, ctx=ctx)
    np.testing.assert_array_equal(frame.lit, plain.lit)
    np.testing.assert_array_equal(frame.image, plain.image)
    assert plain.depth is None
    with pytest.raises(ValueError, match="depht"):
        shadowvol.render(scene, outputs=("depht",), ctx=ctx)


def test_save_masks_of_a_frame_holds_its_camera_and_ground_truth(scene, ctx, tmp_path):
    frame = shadowvol.render(scene, outputs=("depth", "object_id"), ctx=ctx)
    save_masks(tmp_path / "f.npz", frame)
    with np.load(tmp_path / "f.npz") as saved:
        np.testing.assert_array_equal(saved["lit"], frame.lit)
        np.testing.assert_array_equal(saved["coverage"], frame.coverage)
        np.testing.assert_array_equal(saved["depth"], frame.depth)
        np.testing.assert_array_equal(saved["object_id"], frame.object_id)
        for name, value in frame.calibration.arrays().items():
            np.testing.assert_array_equal(saved[name], value)
        assert {"K", "camera_to_world", "world_to_camera"} <= set(saved.files)
    # the ray tracer's frame the same way
    truth = raytrace.ground_truth(scene, outputs=["depth"])
    save_masks(tmp_path / "r.npz", truth)
    with np.load(tmp_path / "r.npz") as saved:
        np.testing.assert_array_equal(saved["K"], frame.calibration.K)
        np.testing.assert_array_equal(saved["lit"], truth.lit)


def test_a_frame_without_its_masks_is_refused_by_name(scene, ctx, tmp_path):
    with Renderer(scene, ctx) as r:
        lean = r.render(outputs=("depth",))   # the low-level call: exactly what is named
    assert lean.lit is None and lean.coverage is None
    with pytest.raises(ValueError, match="no lit and no coverage.*add 'lit', 'coverage'"):
        save_masks(tmp_path / "x.npz", lean)
    with pytest.raises(ValueError, match="needs lit and coverage, got None"):
        save_masks(tmp_path / "x.npz", lean.lit, lean.coverage)
    assert not (tmp_path / "x.npz").exists()
