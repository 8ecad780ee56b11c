"""The reference masks against the float64 brute-force check (tests/exact.py) where a float32
witness is most easily wrong (issue 10): small things far from the origin under a low sun, a
huge ground quad, a card right beside a point light, grazing light at almost flat concave
creases.  The old margins (64 float32 spacings of the world's coordinates) failed each of
these; `raytrace.tolerances` says why the new ones do not.

Budget (`check_exact`): zero interior mismatches, at most EXACT_EDGE_BUDGET of the pixels in
all.  The random versions of these scenes are in test_reference_property.py.
"""

from __future__ import annotations

import pytest
from exact import check_exact, exact_masks
from worlds import card_by_light, grazing_crease, kerbs, lamp_room

import raytrace
from shadowvol.compare.maskdiff import edge_pixels


@pytest.mark.parametrize("offset", [0.0, 1e3, 1e4, 1e5, 1e6])
def test_kerbs_far_from_the_origin_keep_their_shadows(request, offset):
    """5 cm kerbs under a 3-degree sun, translated by up to 1e6 on every axis (the old margin
    lost 9,064 pixels at 1e4 and 20,704 at 1e6 of a larger image)."""
    scene = kerbs([offset, -0.37 * offset, 0.71 * offset], elevation=3.0, turn=7.0)
    check_exact(request, scene)
    # and the same masks as at the origin, but for pixels at edges
    near_origin = raytrace.shadow_masks(kerbs([0.0, 0.0, 0.0], elevation=3.0, turn=7.0))[0]
    assert (raytrace.shadow_masks(scene)[0] != near_origin).mean() < 0.01


@pytest.mark.parametrize("turn", [0.0, 31.0])
@pytest.mark.parametrize("ground", [1e5, 1e6, 1e7])
def test_a_huge_ground_quad_does_not_open_the_lamp_shade(request, ground, turn):
    """A lamp shade round a point light and a cube on a ground quad up to 1e7 wide, off
    centre, with a low sun too: the light reaches only the patch below the shade (the old light
    margin, of the whole scene's coordinates, was 3.8 units on a 1e6 quad)."""
    scene = lamp_room(ground, offset=[0.3 * ground, 0.0, -0.2 * ground], turn=turn,
                      sun_elevation=4.0)
    check_exact(request, scene)


@pytest.mark.parametrize("offset", [0.0, 1e3])
@pytest.mark.parametrize("card, gap", [(2e-5, 1e-5), (2e-4, 1e-4), (1e-3, 3e-4)])
def test_a_card_beside_a_point_light_casts_its_wedge(request, card, gap, offset):
    """A card 2e-5 wide 1e-5 beside the light (inside the old light margin, 2.3e-5: 64,611
    wrong pixels) shadows a wide patch of the floor.  Budget: no interior mismatch, and at
    most one pixel per pixel of the shadow's outline: float32 places the card's corners to
    ~1% of its width here, which moves the outline of its wide shadow by about a pixel (the
    rasterizer's float32 does the same)."""
    scene = card_by_light(card, gap, offset=[offset, 0.5 * offset, -offset], tilt=13.0)
    outline = int(edge_pixels(exact_masks(scene)[0][0]).sum())
    check_exact(request, scene, budget=outline)


@pytest.mark.parametrize("offset", [0.0, 1e4])
@pytest.mark.parametrize("rise, elevation", [(0.1, 0.05), (1.0, 0.5), (3.0, 2.0)])
def test_grazing_light_at_an_almost_flat_crease(request, rise, elevation, offset):
    """A face rising `rise` degrees beyond a hinge, the sun `elevation` degrees over it: the
    floor is in the face's shadow right up to the hinge (the old margin skipped the first
    1.7 cm of such segments on the bunny at 0.05 degrees)."""
    scene = grazing_crease(rise, elevation, rotation=(17.0, 31.0, -9.0),
                           offset=[offset, offset, -offset])
    check_exact(request, scene)
