"""The viewer's moves (shadowvol.view.state) on a camera given by matrices: it keeps its
intrinsics, and a pan by (dx, dy) pixels moves a point at the pan's depth by exactly dx pixels
right and dy up on the screen, through its non-square pixels and off-centre principal point."""

from __future__ import annotations

import numpy as np
from builders import cards_scene, off_centre

from shadowvol.cameras import calibration, project
from shadowvol.view.state import ViewState, orbit, pan, zoom


def test_moves_keep_the_intrinsics_and_pan_moves_by_pixels():
    scene = off_centre(cards_scene(80, 60), aspect=1.4, shift=(0.2, -0.1))
    state = ViewState.of(scene)
    cam = scene.camera
    point = cam.target                       # a point at the pan's depth (one unit ahead)
    before = project(*_matrices(scene), point[None])[0]
    moved = pan(state, 7.0, -4.0, scene.height).camera
    after = project(*_matrices(scene.replace(camera=moved)), point[None])[0]
    np.testing.assert_allclose(after - before, [7.0, 4.0], atol=1e-9)   # dy counts upward
    for new in (moved, orbit(state, 12.0, 5.0).camera, zoom(state, 2.0).camera):
        assert new.matrix_form
        assert (new.fx, new.fy, new.cx, new.cy) == (cam.fx, cam.fy, cam.cx, cam.cy)
        r = new.camera_to_world[:3, :3]
        np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-12)


def _matrices(scene):
    cal = calibration(scene)
    return cal.K, cal.world_to_camera
