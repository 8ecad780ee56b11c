"""The frame as a type (shadowvol.frame): the field table both renderers' results follow, the
one check of the outputs asked for, the light kinds a field exists for."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from shadowvol import frame
from shadowvol.scene import AreaLight, PointLight, SceneError


def test_the_table_gives_the_ground_truth_and_the_mask_file_in_conventions_order():
    assert frame.GROUND_TRUTH == ("depth", "distance", "normal", "object_id", "facing",
                                  "facing_count", "casters")
    assert list(frame.MASK_ARRAYS) == [*frame.GROUND_TRUTH, "lit_count", "samples",
                                       "visibility_exact", "irradiance_exact", "K",
                                       "world_to_camera", "camera_to_world", "light_position",
                                       "light_direction", *frame.LAYERS]
    # the ray tracer's exact outputs: in a mask file when named, never ground truth the
    # rasterizer must produce
    assert frame.EXACT_OUTPUTS == ("visibility_exact", "irradiance_exact")
    assert not set(frame.EXACT_OUTPUTS) & set(frame.GROUND_TRUTH)
    assert frame.MASK_ARRAYS["visibility_exact"] == (np.float64, ("L", "H", "W"))
    assert frame.LAYERS == ("albedo", "ambient", "direct", "direct_shadowed", "shadow_free")
    assert frame.MASK_ARRAYS["direct"] == (np.float32, ("L", "H", "W", 3))
    assert frame.MASK_ARRAYS["albedo"] == (np.float32, ("H", "W", 3))
    assert frame.MASK_ARRAYS["casters"] == (np.uint64, ("L", "H", "W", "K"))
    assert frame.shape("casters", 2, 3, 4, objects=65) == (2, 3, 4, 2)
    assert frame.shape("normal", 2, 3, 4, flat=True) == (12, 3)
    assert np.isinf(frame.blank("depth", (2,))).all() and frame.blank("object_id", (2,)).dtype \
        == np.uint16


def test_both_results_are_frames_that_declare_only_what_they_add():
    from raytrace.groundtruth import GroundTruth
    from shadowvol.raster.result import RenderResult

    base = {f.name for f in dataclasses.fields(frame.Frame)}
    # every array of the base is a field of the table (calibration: its five arrays)
    assert base - {"calibration"} <= set(frame.FIELDS)
    assert set(frame.FIELDS) - base == {"image", "image_srgb", "stencil", "K",
                                        "world_to_camera", "camera_to_world", "light_position",
                                        "light_direction", *frame.EXACT_OUTPUTS}
    for result, adds in ((RenderResult, {"image", "image_srgb", "stencil", "zfail"}),
                         (GroundTruth, set())):
        assert issubclass(result, frame.Frame)
        own = {f.name for f in dataclasses.fields(result)} - base
        assert own == adds, result
        assert own - {"zfail"} <= set(frame.FIELDS)


def test_the_one_output_check():
    assert frame.check_outputs(["casters", "depth"]) == ("depth", "casters")  # table order
    assert frame.check_outputs(None, ("image", "lit"), ("lit",)) == ("lit",)
    with pytest.raises(SceneError, match="outputs: unknown output 'depths'"):
        frame.check_outputs(["depths"])
    with pytest.raises(SceneError, match="--outputs: unknown output 'image'"):
        frame.check_outputs(["image"], key="--outputs")
    with pytest.raises(TypeError, match="sequence of names"):
        frame.check_outputs("depth")
    with pytest.raises(SceneError, match="object_id counts up to 65535"):
        frame.check_outputs(["object_id"], objects=65536)
    assert frame.check_outputs(["object_id"], objects=65535) == ("object_id",)


def test_a_field_of_hard_lights_is_refused_for_an_area_light():
    point = PointLight([0.0, 2.0, 0.0])
    area = AreaLight("sphere", [0.0, 2.0, 0.0], radius=0.2, samples=4)
    frame.check_light_kinds({"stencil", "lit"}, [point])
    frame.check_light_kinds({"lit", "casters"}, [point, area])
    with pytest.raises(ValueError, match="stencil is per hard light"):
        frame.check_light_kinds({"stencil"}, [point, area])


def test_a_frame_derives_cast_umbra_penumbra_and_its_file_arrays():
    from shadowvol.cameras import calibration
    from builders import cards_scene

    scene = cards_scene(4, 2)
    f = frame.Frame(lit=np.array([[[True, False]]]), coverage=np.array([[True, True]]),
                    lit_count=np.array([[[4, 1]]], np.uint16), samples=np.array([4]),
                    facing=np.array([[[True, True]]]),
                    facing_count=np.array([[[4, 4]]], np.uint16),
                    calibration=calibration(scene))
    assert f.cast.tolist() == [[[False, True]]]
    assert f.penumbra.tolist() == [[[False, True]]] and not f.umbra.any()
    assert f.visibility.tolist() == [[[1.0, 0.25]]]
    assert set(f.arrays()) == {"facing", "facing_count", "lit_count", "samples", "K",
                               "world_to_camera", "camera_to_world", "light_position",
                               "light_direction"}
