"""The path tracer's low-discrepancy samples (`raytrace.outlook.path.sobol`): the Sobol points, each
pixel's samples stratified (a (0, m, 2)-net in a chunk's first two dimensions), every coordinate
uniform over pixels and seeds, chunks unrelated to one another, the compiled numbers the numpy ones,
and the image with them unbiased."""

from __future__ import annotations

import numpy as np
import pytest
from builders import cornell, z_limit

from raytrace.outlook.path import sobol
from raytrace.outlook.path.pathtrace import render
from raytrace.outlook.path.sobol import TileSamples


def test_the_unscrambled_points_are_sobol_s():
    """Against scipy's Sobol sequence (Joe and Kuo's directions), which gives point gray(i)
    as its i-th."""
    qmc = pytest.importorskip("scipy.stats.qmc", reason="scipy (the outlook extra) checks it")
    m = 8
    ours = sobol.reverse_bits(sobol.reversed_points(m)).astype(float) / 2 ** 32
    i = np.arange(1 << m)
    theirs = qmc.Sobol(4, scramble=False).random(1 << m)
    np.testing.assert_array_equal(ours[:, i ^ (i >> 1)].T, theirs)


@pytest.mark.parametrize("spp", [16, 64, 256])
def test_each_pixels_samples_are_a_net_in_the_first_two_dimensions(spp):
    """Every elementary box of area 1/spp (2^a x 2^b cells, a + b = m) holds one of a pixel's
    spp samples, in every chunk, for every pixel looked at."""
    m = sobol.bits_for(spp)
    pixels = np.repeat(np.arange(50), spp)
    sample = np.tile(np.arange(spp), 50)
    for chunk in (0, 1, 2, 7):
        u = sobol.to_float64(sobol.chunk_bits(1234, pixels, sample, chunk, 2, m))
        for a in range(m + 1):
            cell = (np.floor(u[0] * 2 ** a) * 2 ** (m - a) + np.floor(u[1] * 2 ** (m - a)))
            counts = np.bincount((pixels * spp + cell).astype(int), minlength=50 * spp)
            assert (counts == 1).all(), (chunk, a)


def test_coordinates_are_uniform_and_chunks_unrelated():
    """Over 4000 pixels x 16 samples: each coordinate's histogram (16 bins) is uniform
    (chi-squared, false alarm 1e-3 over all the tests), and a pixel's sample i in one chunk
    says nothing about its sample i in another (correlation ~ 0)."""
    pixels = np.repeat(np.arange(4000), 16)
    sample = np.tile(np.arange(16), 4000)
    u = {c: sobol.to_float64(sobol.chunk_bits(99, pixels, sample, c, 4, 4)) for c in (0, 1, 2)}
    n = len(pixels)
    for c in u:
        for d in range(4):
            counts = np.bincount((u[c][d] * 16).astype(int), minlength=16)
            chi2 = ((counts - n / 16) ** 2 / (n / 16)).sum()
            assert chi2 < 50.0, (c, d, chi2)  # chi2(15) exceeds 50 with p ~ 1e-5
    limit = z_limit(18) / np.sqrt(n)
    for c0, c1 in ((0, 1), (0, 2), (1, 2)):
        for d0 in (0, 1, 2):
            r = np.corrcoef(u[c0][d0], u[c1][d0])[0, 1]
            assert abs(r) < limit, (c0, c1, d0, r)


def test_the_compiled_numbers_are_the_numpy_numbers():
    pytest.importorskip("numba", reason="the compiled numbers need numba")
    rng = np.random.default_rng(0)
    for spp in (1, 3, 64, 100):
        numpy_, compiled = (TileSamples(7, 256, 300, spp, c) for c in (False, True))
        path = np.sort(rng.permutation(300 * spp)[:200 * spp])
        for chunk, dims, wide in ((0, 2, 0), (3, 3, 2), (4, 4, -1)):
            a, b = numpy_.floats(chunk, path, dims, wide), compiled.floats(chunk, path, dims,
                                                                           wide)
            assert np.array_equal(a[0], b[0]) and (wide < 0 or np.array_equal(a[1], b[1]))
        assert all(np.array_equal(x, y) for x, y in zip(numpy_.camera(), compiled.camera()))


def test_float32_numbers_stay_below_one():
    top = np.array([0xFFFFFFFF, 0xFFFFFF00, 0], np.uint32)
    assert (sobol.to_float32(top) < 1).all() and (sobol.to_float64(top) < 1).all()
    assert sobol.to_float32(top).dtype == np.float32


def test_sobol_and_independent_images_agree_in_expectation(path_shading):
    """The Cornell box at 32 x 32, 64 samples, depth 4: block means of the Sobol image against
    the independent one's (whose variance estimates are exact; the Sobol image's are an upper
    bound), z-test over 8 x 8 blocks and the whole image."""
    scene = cornell(32)
    a = render(scene, spp=64, seed=1, max_depth=4, progress=False)
    b = render(scene, spp=64, seed=2, max_depth=4, sampler="independent", progress=False)
    z = []
    for block in (8, 32):
        shape = (32 // block, block, 32 // block, block, 3)
        ma, mb = (r.image.reshape(shape).mean(axis=(1, 3)) for r in (a, b))
        va, vb = (r.variance.reshape(shape).sum(axis=(1, 3)) / block ** 4 for r in (a, b))
        z.append(((ma - mb) / np.sqrt(va + vb)).ravel())
    z = np.concatenate(z)
    assert np.abs(z).max() < z_limit(z.size), np.abs(z).max()
