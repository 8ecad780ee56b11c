"""The auto method's near-clip volume test (no GL needed): conservative, and not uselessly so."""

from __future__ import annotations

import numpy as np
import pytest

from shadowvol.raster.methods import choose, near_clip_planes, needs_zfail
from shadowvol.raster.projection import near_rectangle
from shadowvol.scene import Camera, DirectionalLight, PointLight

EXTENT = 20.0


def _hull_samples(camera, aspect, light4, rng, n=4000):
    """Points of the convex hull of the light and the near rectangle (for a directional light:
    the rectangle swept toward the light, up to 2 extents)."""
    rect = near_rectangle(camera, aspect)
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
    zfail = needs_zfail(bounds, camera, 4 / 3, light4, EXTENT)
    pts = _hull_samples(camera, 4 / 3, light4, rng)
    inside = ((pts[None] >= bounds[:, None, 0]) & (pts[None] <= bounds[:, None, 1])).all(-1)
    reached = inside.any(axis=1)
    assert not (reached & ~zfail).any(), "z-pass chosen for a box inside the near-clip volume"
    assert (~zfail).sum() > 0.3 * len(bounds)  # and most boxes far from it still get z-pass


def test_hull_planes_hold_the_light_and_the_rectangle():
    camera = Camera(eye=[0, 1, 5], target=[0, 0, 0])
    light4 = PointLight([2, 6, 1]).homogeneous
    planes = near_clip_planes(camera, 1.5, light4)
    pts = np.concatenate([near_rectangle(camera, 1.5), light4[None, :3]])
    assert (pts @ planes[:, :3].T + planes[:, 3] <= 1e-9).all()


def test_light_in_the_near_plane_makes_every_caster_zfail():
    camera = Camera(eye=[0, 0, 5], target=[0, 0, 0], near=1.0)
    light4 = PointLight([3, 0, 4]).homogeneous  # z = 4: in the near plane
    assert near_clip_planes(camera, 1.0, light4) is None
    far_box = np.array([[[-1, -1, -30], [1, 1, -29]]], float)
    assert choose("auto", far_box, camera, 1.0, light4, EXTENT).tolist() == [True]
    assert choose("zpass", far_box, camera, 1.0, light4, EXTENT).tolist() == [False]
    with pytest.raises(ValueError, match="method"):
        choose("zfial", far_box, camera, 1.0, light4, EXTENT)
