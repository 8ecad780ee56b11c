"""The auto method's near-clip volume test (no GL needed): conservative, and not uselessly so."""

from __future__ import annotations

import numpy as np
import pytest

from shadowvol.raster.methods import choose, near_clip_planes, needs_zfail
from shadowvol.raster.projection import near_rectangle
from shadowvol.scene import Camera, DirectionalLight, PointLight

EXTENT = 20.0


def _hull_samples(camera, size, light4, rng, n=4000):
    """Points of the convex hull of the light and the near rectangle (for a directional light:
    the rectangle swept toward the light, up to 2 extents)."""
    rect = near_rectangle(camera, size)
    w = rng.dirichlet(np.ones(4), size=n)
    base = w @ rect
    t = rng.random((n, 1))
    if light4[3]:
        return base + t * (light4[:3] - base)
    return base + t * 2 * EXTENT * light4[:3]


@pytest.mark.parametrize("seed", range(20))
def test_never_zpass_for_a_box_the_hull_reaches(seed):
    rng = np.random.default_rng(seed)
    camera = Camera(eye=rng.uniform(-3, 3, 3), target=rng.uniform(-3, 3, 3) + [0, 0, 0.1],
                    near=rng.choice([0.05, 0.5, 1.0]))
    light = (PointLight(rng.uniform(-5, 5, 3)) if seed % 2
             else DirectionalLight(rng.normal(size=3)))
    light4 = light.homogeneous
    lo = rng.uniform(-4, 4, (300, 3))
    bounds = np.stack([lo, lo + rng.uniform(0.05, 2.0, (300, 3))], axis=1)
    zfail = needs_zfail(bounds, camera, (4, 3), light4, EXTENT)
    pts = _hull_samples(camera, (4, 3), light4, rng)
    inside = ((pts[None] >= bounds[:, None, 0]) & (pts[None] <= bounds[:, None, 1])).all(-1)
    reached = inside.any(axis=1)
    assert not (reached & ~zfail).any(), "z-pass chosen for a box inside the near-clip volume"
    assert (~zfail).sum() > 0.3 * len(bounds)  # and most boxes far from it still get z-pass


def test_hull_planes_hold_the_light_and_the_rectangle():
    camera = Camera(eye=[0, 1, 5], target=[0, 0, 0])
    light4 = PointLight([2, 6, 1]).homogeneous
    planes = near_clip_planes(camera, (3, 2), light4)
    pts = np.concatenate([near_rectangle(camera, (3, 2)), light4[None, :3]])
    assert (pts @ planes[:, :3].T + planes[:, 3] <= 1e-9).all()


def test_light_in_the_near_plane_makes_every_caster_zfail():
    camera = Camera(eye=[0, 0, 5], target=[0, 0, 0], near=1.0)
    light4 = PointLight([3, 0, 4]).homogeneous  # z = 4: in the near plane
    assert near_clip_planes(camera, (1, 1), light4) is None
    far_box = np.array([[[-1, -1, -30], [1, 1, -29]]], float)
    assert choose("auto", far_box, camera, (1, 1), light4, EXTENT).tolist() == [True]
    assert choose("zpass", far_box, camera, (1, 1), light4, EXTENT).tolist() == [False]
    with pytest.raises(ValueError, match="method"):
        choose("zfial", far_box, camera, (1, 1), light4, EXTENT)


@pytest.mark.parametrize("seed", range(6))
def test_the_separation_is_the_per_corner_definition(seed):
    """needs_zfail against its definition taken corner by corner in plain Python: z-pass
    exactly when some hull plane has all 8 box corners beyond the margin, or every hull
    corner (the near rectangle and the light) lies below the box's low face or above its high
    face on some axis, by the margin."""
    from shadowvol.raster.methods import FAR_APEX_EXTENTS, NEAR_CLIP_MARGIN
    rng = np.random.default_rng(100 + seed)
    camera = Camera(eye=rng.uniform(-3, 3, 3), target=rng.uniform(-3, 3, 3) + [0, 0, 0.1],
                    near=rng.choice([0.05, 0.5]))
    light = (PointLight(rng.uniform(-5, 5, 3)) if seed % 2
             else DirectionalLight(rng.normal(size=3)))
    light4 = light.homogeneous
    lo = rng.uniform(-6, 6, (60, 3))
    bounds = np.stack([lo, lo + rng.uniform(0.05, 3.0, (60, 3))], axis=1)
    # a floor under everything, separated by its face alone
    bounds = np.concatenate([bounds, [[[-50, -40, -50], [50, -39, 50]]]])
    planes = near_clip_planes(camera, (4, 3), light4)
    rect = near_rectangle(camera, (4, 3))
    apex = (light4[:3] if light4[3]
            else rect.mean(axis=0) + light4[:3] * (FAR_APEX_EXTENTS * EXTENT))
    hull = [*rect, apex]
    margin = NEAR_CLIP_MARGIN * EXTENT
    expected = []
    for (x0, y0, z0), (x1, y1, z1) in bounds:
        corners = [(x, y, z) for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)]
        by_plane = any(all(float(np.dot(pl[:3], c) + pl[3]) > margin for c in corners)
                       for pl in planes)
        by_face = any(all(h[a] < (x0, y0, z0)[a] - margin for h in hull)
                      or all(h[a] > (x1, y1, z1)[a] + margin for h in hull) for a in range(3))
        expected.append(not (by_plane or by_face))
    assert needs_zfail(bounds, camera, (4, 3), light4, EXTENT).tolist() == expected
    if min(h[1] for h in hull) > -39 + margin:   # the whole hull above the floor: its face
        assert not expected[-1]                  # separates them, and z-pass is chosen
