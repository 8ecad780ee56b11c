"""`slides.fit` of a camera given by matrices: the panel shows what the look-at camera of the
same view would show (the same K, up to rounding), and non-square pixels and an off-centre
principal point keep their shape and their place in the view."""

from __future__ import annotations

import numpy as np
import pytest
from builders import cards_scene, off_centre

from shadowvol.cameras import calibration
from shadowvol.course.slides import fit


@pytest.mark.parametrize("panel, cover", [((60, 60), False), ((60, 60), True),
                                          ((200, 50), False), ((200, 50), True)])
def test_fit_of_matrices_is_fit_of_the_look_at_camera(panel, cover):
    look_at = cards_scene(80, 60)
    matrices = off_centre(look_at, aspect=1.0, shift=(0.0, 0.0))    # the same camera, as K
    np.testing.assert_array_equal(calibration(matrices).K, calibration(look_at).K)
    want = calibration(fit(look_at, *panel, samples=2, cover=cover))
    got = calibration(fit(matrices, *panel, samples=2, cover=cover))
    np.testing.assert_allclose(got.K, want.K, rtol=1e-12)
    np.testing.assert_array_equal(got.camera_to_world, want.camera_to_world)


def test_fit_keeps_the_pixels_shape_and_the_principal_point_in_place():
    scene = off_centre(cards_scene(80, 60))
    fitted = fit(scene, 60, 60)
    K0, K1 = calibration(scene).K, calibration(fitted).K
    assert K1[0, 0] / K1[1, 1] == pytest.approx(K0[0, 0] / K0[1, 1], rel=1e-12)
    s = 60 / 80                                    # the width fits: 80 -> 60, centred
    np.testing.assert_allclose(K1[0, 2], K0[0, 2] * s, rtol=1e-12)
    np.testing.assert_allclose(K1[1, 2], K0[1, 2] * s + (60 - 60 * s) / 2, rtol=1e-12)
