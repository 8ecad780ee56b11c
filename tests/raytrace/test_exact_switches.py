"""The shadow switches in the exact visibility (raytrace.exact_soft; docs/CONVENTIONS.md,
"Shadow switches"): an object with `cast_shadows` off is no occluder, a pixel whose object has
`receive_shadows` off and every pixel of a light with `shadows` off see the light's part on
their side whole (V = 1 under a light wholly in front), as the samples' facing test alone says.
"""

from __future__ import annotations

import numpy as np
import pytest
from builders import LIGHT_SIDE, LIGHT_Y, MATTE, floor_points, square_light, \
    square_over_floor, switched

from raytrace.exact_soft import exact_visibility
from raytrace.groundtruth import ground_truth
from shadowvol.primitives import box

ROUNDING = 1e-12
SCENE = square_over_floor(square_light(4), size=32)


def _rect_irradiance(p, half, y):
    """The irradiance at floor points p (..., 3) from the unit-radiance square
    [-half, half]^2 at height y, parallel to the floor (the form factor's corner sums, x π)."""
    def corner(a, b, c):
        A, B = a / c, b / c
        sa, sb = np.sqrt(1 + A * A), np.sqrt(1 + B * B)
        return (A / sa * np.arctan(B / sa) + B / sb * np.arctan(A / sb)) / 2

    c = y - p[..., 1]
    x, z = p[..., 0], p[..., 2]
    return (corner(half - x, half - z, c) - corner(-half - x, half - z, c)
            - corner(half - x, -half - z, c) + corner(-half - x, -half - z, c))


@pytest.fixture(scope="module")
def shadowed():
    found = exact_visibility(SCENE)
    p, floor = floor_points(SCENE)
    # the occluder does shadow the floor: a penumbra and an umbra
    assert (found.visibility[0][floor] < 0.5).sum() > 20
    return p, floor


@pytest.mark.parametrize("switches", [dict(cast=[1]), dict(cast=[0, 1]), dict(receive=[0]),
                                      dict(lights=[0])],
                         ids=["occluder casts nothing", "no object casts (no cluster)",
                              "floor receives nothing", "light casts nothing"])
def test_a_switch_leaves_the_floor_the_whole_light(shadowed, switches):
    p, floor = shadowed
    found = exact_visibility(switched(SCENE, **switches))
    assert np.abs(found.visibility[0][floor] - 1).max() <= ROUNDING
    want = _rect_irradiance(p, LIGHT_SIDE / 2, LIGHT_Y)
    assert np.abs(found.irradiance[0][floor] / want[floor] - 1).max() <= ROUNDING


def test_a_non_casting_object_is_no_occluder_beside_a_casting_one():
    """A casting box beside the non-casting square: the floor sees exactly what it sees
    with the square taken out of the scene."""
    cube = box("cube", center=[-0.9, 0.6, 0.4], size=[0.4, 0.4, 0.4], material=MATTE)
    both = SCENE.replace(objects=[*SCENE.objects, cube])
    off = exact_visibility(switched(both, cast=[1]))
    alone = SCENE.replace(objects=[SCENE.objects[0], cube])
    ref = exact_visibility(alone)
    _, floor = floor_points(SCENE)
    floor &= ground_truth(alone, outputs=("object_id",)).object_id == 1
    assert ((ref.visibility[0] < 0.99) & floor).sum() > 5    # the box's shadow is there
    assert np.abs(off.visibility[0] - ref.visibility[0])[floor].max() <= ROUNDING
    assert np.abs(off.irradiance[0] - ref.irradiance[0])[floor].max() <= ROUNDING
    # and the square (not a caster) still hides the floor from the camera: its own pixels
    # are lit by the whole light above it
    square = ground_truth(both, outputs=("object_id",)).object_id == 2
    assert square.sum() > 10 and np.abs(off.visibility[0][square] - 1).max() <= ROUNDING
