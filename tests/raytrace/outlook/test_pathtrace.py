"""The path tracer: furnace, depth 1 against the masks' direct lighting, unbiased Russian
roulette, the Phong normalisation, reproducibility."""

from __future__ import annotations

import math

import numpy as np
import pytest
from builders import QUADRATURE_ALLOWANCE, block_means, cornell, furnace, z_limit

from raytrace.outlook import brdf
from raytrace.outlook.direct import direct_lighting
from raytrace.outlook.path import pathtrace
from raytrace.outlook.path.pathtrace import render
from raytrace.outlook.whitted import render as whitted_render
from shadowvol.primitives import box, plane
from shadowvol.scene import AreaLight, Camera, Material, Scene


def test_furnace_converges_to_emission_over_one_minus_albedo(path_shading):
    rho, emitted = np.array([0.3, 0.5, 0.7]), 1.0
    expected = emitted / (1.0 - rho)
    result = render(furnace(rho, [emitted] * 3), spp=128, seed=1)
    assert result.shading == path_shading
    mean, var = block_means(result.image, result.variance, block=4)
    whole, whole_var = block_means(result.image, result.variance, block=16)
    z = np.concatenate([((mean - expected) / np.sqrt(var)).ravel(),
                        ((whole - expected) / np.sqrt(whole_var)).ravel()])
    assert np.abs(z).max() < z_limit(z.size), (whole, expected, z)
    # the statistics are sharp enough to see a 2% error in the whole image's mean
    assert (z_limit(z.size) * np.sqrt(whole_var) < 0.02 * expected).all()


def test_depth_one_equals_direct_lighting_from_the_masks(path_shading):
    scene = cornell(48)
    result = render(scene, spp=64, seed=3, max_depth=1, jitter=False)
    assert result.shading == path_shading
    reference = direct_lighting(scene, splits=3)
    mean, var = block_means(result.image, result.variance, block=4)
    ref, _ = block_means(reference, np.zeros_like(reference), block=4)
    scale = np.median(reference, axis=(0, 1))
    allowed = z_limit(mean.size) * np.sqrt(var) + QUADRATURE_ALLOWANCE * scale
    bad = np.abs(mean - ref) > allowed
    assert not bad.any(), f"{bad.sum()} of {bad.size} block means differ: " \
        f"{mean[bad][:4]} vs {ref[bad][:4]}"
    # and the test is sharp: a 5% error in the light would fail a quarter of the blocks
    assert (np.abs(0.05 * ref) > allowed).sum() > 0.25 * ref.size


def test_russian_roulette_is_unbiased(path_shading):
    """Mean over seeds with roulette from the first bounce vs a render without roulette (same
    depth bound): a z-test per 4x4-pixel region and channel, false alarm FALSE_ALARM."""
    scene = cornell(24)
    depth = 6
    runs = [render(scene, spp=32, seed=s, max_depth=depth, rr_start=1) for s in range(8)]
    low = np.mean([r.image for r in runs], axis=0)
    low_var = np.sum([r.variance for r in runs], axis=0) / len(runs) ** 2
    ref = render(scene, spp=384, seed=100, max_depth=depth, rr_start=depth + 1)
    assert ref.shading == path_shading
    z = []
    for block in (4, 24):  # regions, and the whole image
        a, va = block_means(low, low_var, block)
        b, vb = block_means(ref.image, ref.variance, block)
        z.append(((a - b) / np.sqrt(va + vb)).ravel())
    z = np.concatenate(z)
    assert np.abs(z).max() < z_limit(z.size), np.abs(z).max()
    # sharp enough to see a 6% bias of the whole image (e.g. survival weights 1 / 1.06 q)
    assert (0.06 * b > z_limit(z.size) * np.sqrt(va + vb)).all(), np.sqrt(va + vb) / b


def test_same_seed_same_image_other_seed_other_image(path_shading):
    scene = cornell(16)
    a = render(scene, spp=2, seed=7)
    b = render(scene, spp=2, seed=7)
    c = render(scene, spp=2, seed=8)
    assert a.shading == path_shading
    assert np.array_equal(a.image, b.image)
    assert not np.array_equal(a.image, c.image)


def test_the_image_does_not_depend_on_the_threads(monkeypatch, path_shading):
    """Tiles of whole rows, one random stream each, summed in tile order: one thread or two
    give the same bytes."""
    monkeypatch.setattr(pathtrace, "TILE_PATHS", 64)  # 16x16 at spp 2: 8 tiles
    scene = cornell(16)
    images = []
    for threads in (1, 2):
        monkeypatch.setattr(pathtrace, "cpu_threads", lambda threads=threads: threads)
        images.append(render(scene, spp=2, seed=5, progress=False))
    assert np.array_equal(images[0].image, images[1].image)
    assert np.array_equal(images[0].variance, images[1].variance)
    assert images[0].rays == images[1].rays
    assert images[0].shading == path_shading


def test_cosine_sampling_has_the_cosine_lobe_moments():
    """The path tracer's cosine sampler (n plus a uniform point of the sphere, normalised) and
    the framed one radiosity uses: E[cos] = 2/3, E[cos^2] = 1/2, never below the surface, the
    azimuth uniform (E[t] = E[b] = 0 about any normal), 4e5 samples each, 5 sigma."""
    rng = np.random.default_rng(4)
    k = 400_000
    axis = np.array([0.3, -0.8, 0.52])
    axis /= np.linalg.norm(axis)
    n = np.tile(axis, (k, 1))
    t, b = brdf.frame(n[:1])
    for wi in (brdf.cosine_hemisphere_rows(rng, np.ascontiguousarray(n.T, np.float32)).T,
               brdf.cosine_hemisphere_rows(rng, np.ascontiguousarray(n.T)).T,
               brdf.cosine_hemisphere(rng, n)):
        wi = wi.astype(np.float64)
        np.testing.assert_allclose(np.linalg.norm(wi, axis=1), 1.0, atol=1e-6)
        c = wi @ axis
        assert c.min() >= -1e-6
        for moment, expected, sd in ((c, 2 / 3, np.sqrt(1 / 2 - 4 / 9)),
                                     (c * c, 1 / 2, np.sqrt(1 / 3 - 1 / 4)),
                                     (wi @ t[0], 0.0, 0.5), (wi @ b[0], 0.0, 0.5)):
            assert abs(moment.mean() - expected) < 5 * sd / np.sqrt(k), (expected, moment.mean())


def test_phong_normalisation_conserves_energy():
    """Directional albedo of the normalised glossy lobe: ks at normal incidence, below ks at
    grazing, never above (estimated by sampling the lobe itself, 4e5 samples per case)."""
    rng = np.random.default_rng(0)
    k = 400_000
    n = np.tile([0.0, 0.0, 1.0], (k, 1))
    ks = np.full((k, 3), 0.6)
    kd = np.zeros((k, 3))
    for s, theta, low, high in ((20.0, 0.0, 0.99, 1.01), (5.0, 0.0, 0.99, 1.01),
                                (20.0, 1.45, 0.05, 0.99)):
        wo = np.tile([math.sin(theta), 0.0, math.cos(theta)], (k, 1))
        shin = np.full(k, s)
        wi = brdf.phong_sample(rng, np.zeros(k), shin, n, wo)
        f = brdf.phong_eval(kd, ks, shin, n, wo, wi)
        pdf = brdf.phong_pdf(np.zeros(k), shin, n, wo, wi)
        cos = np.maximum(wi[:, 2], 0.0)
        albedo = np.where(pdf > 0, f[:, 0] * cos / np.where(pdf > 0, pdf, 1), 0.0).mean()
        assert low * 0.6 < albedo < high * 0.6, (s, theta, albedo)


def test_kd_plus_ks_above_one_is_scaled_down():
    kd, ks = brdf.normalised_phong(np.array([[0.8, 0.8, 0.8], [0.2, 0.1, 0.0]]),
                                   np.array([[0.5, 0.5, 0.5], [0.1, 0.1, 0.1]]))
    np.testing.assert_allclose(kd[0] + ks[0], 1.0)
    np.testing.assert_allclose(kd[0] / ks[0], 0.8 / 0.5)
    np.testing.assert_array_equal(kd[1], [0.2, 0.1, 0.0])


@pytest.mark.parametrize("bad", [0, -1, 1.5, True])
def test_bad_spp_is_refused(bad):
    with pytest.raises(ValueError, match="spp"):
        render(cornell(8), spp=bad)


def test_an_area_light_is_its_samples_as_in_whitted(path_shading):
    """An area light in `scene.lights` (not emissive geometry): the path tracer's next-event
    estimate sums its samples, each weighted by its cosine at the light, as the Whitted
    tracer's direct term does.  Lambertian, no ambient, pixel centres, depth 1: nothing is
    random, so the two images are equal but for float32 rounding and shadow-edge pixels (the
    two tracers offset their shadow rays differently)."""
    lambert = Material(diffuse=[0.7, 0.6, 0.5], specular=[0, 0, 0])
    light = AreaLight("rect", [0.4, 3.0, 0.2], normal=[0.3, -1.0, 0.1], size=[1.2, 0.8],
                      samples=9, intensity=2.0)
    scene = Scene(camera=Camera(eye=[0.0, 3.0, 4.0], target=[0.0, 0.3, 0.0], fov_y=50.0),
                  objects=[plane("floor", size=(8.0, 8.0), material=lambert),
                           box("box", center=(0.0, 0.6, 0.0), size=(0.8, 1.2, 0.8),
                               material=lambert)],
                  lights=[light], width=48, height=36, ambient=[0, 0, 0],
                  background=[0, 0, 0])
    traced = render(scene, spp=1, seed=0, max_depth=1, jitter=False)
    assert traced.shading == path_shading
    traced = traced.image
    whitted = whitted_render(scene, max_depth=0)
    close = np.isclose(traced, whitted, rtol=1e-4, atol=1e-6).all(axis=2)
    assert close.mean() > 0.97, f"{(~close).sum()} pixels differ"
    # the test is sharp: the cosine at the light matters (the light is tilted), and the box's
    # penumbra is in the picture
    assert (whitted > 0).any(axis=2).mean() > 0.5
    levels = np.unique(np.round(whitted[..., 0], 6))
    assert len(levels) > 40
