"""Planar projected shadows (Blinn 1988): the projection matrix and the anti-shadow test."""

import numpy as np
import pytest

from shadowvol.raster.planar.matrix import (
    casts_shadow,
    homogeneous_light,
    plane_equation,
    project_points,
    projection_matrix,
)
from shadowvol.scene import DirectionalLight, PointLight, SpotLight

FOLDER_GL = False  # numpy only: no test here renders (conftest.py)

EXACT = 1e-12       # hand-worked numbers, exact up to float rounding
GEOMETRY = 1e-9     # on-plane and collinearity residuals for random points (relative to scale)


def test_hand_computed_point_light_onto_the_floor():
    # Floor y = 0: P = (0, 1, 0, 0).  Light L = (0, 4, 0, 1), P . L = 4.
    # M = 4 I - L P^T: L P^T has the column L in position y:
    #   [[4, 0, 0, 0],        row x: 4x - 0*y
    #    [0, 0, 0, 0],        row y: 4y - 4y = 0
    #    [0, 0, 4, 0],        row z: 4z
    #    [0, -1, 0, 4]]       row w: 4 - y
    # The point (1, 2, 0): M X = (4, 0, 0, 2) -> (2, 0, 0): the line from (0, 4, 0) through
    # (1, 2, 0) reaches y = 0 at twice the distance, x = 2.
    M = projection_matrix([0, 0, 0], [0, 1, 0], [0, 4, 0, 1])
    np.testing.assert_allclose(M, [[4, 0, 0, 0], [0, 0, 0, 0], [0, 0, 4, 0], [0, -1, 0, 4]],
                               atol=EXACT)
    np.testing.assert_allclose(M @ [1, 2, 0, 1], [4, 0, 0, 2], atol=EXACT)
    np.testing.assert_allclose(project_points(M, [[1, 2, 0]]), [[2, 0, 0]], atol=EXACT)


def test_hand_computed_directional_light_onto_a_tilted_plane():
    # Plane x + y = 1 (normal (1, 1, 0)/sqrt 2 through (1, 0, 0)).  A light travelling along
    # t = (-1, 0, 0) (coming from +x).  The point (3, 0.5, 7) moves along t until
    # x + 0.5 = 1: to (0.5, 0.5, 7).
    M = projection_matrix([1, 0, 0], [1, 1, 0], DirectionalLight([-1, 0, 0]))
    np.testing.assert_allclose(project_points(M, [[3, 0.5, 7]]), [[0.5, 0.5, 7]], atol=EXACT)
    # The same with the homogeneous light written out: (-t, 0) = (1, 0, 0, 0).
    M2 = projection_matrix([1, 0, 0], [1, 1, 0], [1, 0, 0, 0])
    np.testing.assert_allclose(M2, M, atol=EXACT)


def test_directional_light_sign_convention():
    # A light travelling straight down projects a point straight down, never up through it.
    light = DirectionalLight([0, -1, 0])
    np.testing.assert_allclose(homogeneous_light(light), [0, 1, 0, 0])
    M = projection_matrix([0, 0, 0], [0, 1, 0], light)
    np.testing.assert_allclose(project_points(M, [[0.3, 5, -2]]), [[0.3, 0, -2]], atol=EXACT)
    # Slanted: travelling along (1, -1, 0)/sqrt 2, the point (0, 2, 0) lands at (2, 0, 0),
    # i.e. it moved along +t, not -t.
    M = projection_matrix([0, 0, 0], [0, 1, 0], DirectionalLight([1, -1, 0]))
    moved = project_points(M, [[0, 2, 0]])[0] - [0, 2, 0]
    np.testing.assert_allclose(moved, [2, -2, 0], atol=EXACT)


@pytest.mark.parametrize("light", [
    PointLight([1.0, 6.0, -2.0]),
    SpotLight([-3.0, 2.5, 1.0], [0, -1, 0]),
    DirectionalLight([0.3, -1.0, 0.2]),
    DirectionalLight([0.3, 1.0, 0.2]),       # light from below the plane: M's sign flips
    [2.0, -5.0, 1.0, 1.0],                   # a point light below the plane
])
def test_random_points_land_on_the_plane_on_the_line_through_the_light(light):
    rng = np.random.default_rng(7)
    point, normal = np.array([0.5, 0.2, -0.1]), np.array([0.1, 1.0, -0.2])
    P = plane_equation(point, normal)
    L = homogeneous_light(light)
    M = projection_matrix(point, normal, light)
    X = rng.uniform(-3, 3, (200, 3))
    Y = project_points(M, X)
    # On the plane.
    assert np.max(np.abs(Y @ P[:3] + P[3])) < GEOMETRY * 10
    # Collinear with the light and the original point.
    if L[3] == 0:
        direction = L[:3]
        np.testing.assert_allclose(np.cross(Y - X, direction), 0, atol=GEOMETRY * 10)
    else:
        l = L[:3] / L[3]
        np.testing.assert_allclose(np.cross(Y - l, X - l), 0, atol=GEOMETRY * 100)
    # A point already on the plane stays put.
    on = Y[:10]
    np.testing.assert_allclose(project_points(M, on), on, atol=GEOMETRY * 10)
    # Real shadow points get w > 0 (GL clips w < 0), whichever side the light is on.
    real = casts_shadow(point, normal, light, X)
    assert real.any()
    w = (np.concatenate([X, np.ones((len(X), 1))], axis=1) @ M.T)[:, 3]
    assert np.all(w[real] > 0)


def test_anti_shadow_check():
    # Floor y = 0, point light at height 4: points between 0 and 4 cast, points above the light
    # or below the floor do not.
    light = PointLight([0, 4, 0])
    pts = [[1, 2, 0], [1, 0, 0], [1, 5, 0], [1, -1, 0], [1, 3.999, 2]]
    np.testing.assert_array_equal(casts_shadow([0, 0, 0], [0, 1, 0], light, pts),
                                  [True, True, False, False, True])
    # The point above the light projects through it to the far side: an anti-shadow at
    # x = -4 (line from (0, 4, 0) through (1, 5, 0) continued backwards reaches y = 0 at x = -4).
    M = projection_matrix([0, 0, 0], [0, 1, 0], light)
    np.testing.assert_allclose(project_points(M, [[1, 5, 0]]), [[-4, 0, 0]], atol=EXACT)
    # A directional light travelling down: everything above the floor casts, however high.
    sun = DirectionalLight([0, -1, 0])
    np.testing.assert_array_equal(casts_shadow([0, 0, 0], [0, 1, 0], sun, pts),
                                  [True, True, True, False, True])


def test_degenerate_lights_raise():
    with pytest.raises(ValueError, match="lies in"):
        projection_matrix([0, 0, 0], [0, 1, 0], PointLight([3, 0, 1]))
    with pytest.raises(ValueError, match="parallel"):
        projection_matrix([0, 0, 0], [0, 1, 0], DirectionalLight([1, 0, 0]))
    with pytest.raises(ValueError, match="non-zero"):
        projection_matrix([0, 0, 0], [0, 0, 0], PointLight([3, 1, 1]))
