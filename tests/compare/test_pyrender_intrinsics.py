"""A camera given by matrices through the pyrender bridge: our fx, fy, cx, cy and
camera_to_world become pyrender's IntrinsicsCamera and pose and back, and pyrender, drawing with
it, covers the pixels our ray tracer covers (non-square pixels, an off-centre principal point)."""

from __future__ import annotations

import numpy as np
from builders import cards_scene, off_centre

import raytrace
from shadowvol.compare import pyrender_peer as pb
from shadowvol.compare.maskdiff import mask_report
from shadowvol.scene import DirectionalLight


def _scene():
    return off_centre(cards_scene(96, 72, DirectionalLight([0.3, -1.0, -0.2])))


def test_a_matrix_camera_goes_to_pyrender_and_back():
    scene = _scene()
    back = pb.from_pyrender(pb.to_pyrender(scene), scene.width, scene.height)
    cam = back.camera
    assert cam.matrix_form
    assert (cam.fx, cam.fy, cam.cx, cam.cy, cam.near) == (
        scene.camera.fx, scene.camera.fy, scene.camera.cx, scene.camera.cy, scene.camera.near)
    np.testing.assert_allclose(cam.camera_to_world, scene.camera.camera_to_world, atol=1e-12)


def test_pyrender_covers_what_we_cover_through_the_same_intrinsics():
    scene = _scene()
    lit, coverage = pb.pyrender_shadow_masks(scene)
    ref_lit, ref_cov = raytrace.shadow_masks(scene)
    row = mask_report(lit[:0], coverage, ref_lit[:0], ref_cov)[0]   # the coverage's row
    assert row["interior"] == 0 and row["total"] <= 0.01 * ref_cov.size, row
    assert 0.2 * ref_cov.size < ref_cov.sum() < ref_cov.size   # there are edges to get wrong
