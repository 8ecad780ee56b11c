"""Low-discrepancy samples for the path tracer: Owen-scrambled Sobol points, per pixel, padded
in chunks of up to four dimensions (Burley 2020, "Practical Hash-based Owen Scrambling").

Each pixel's `spp` samples of a chunk (the camera's pixel jitter; at a bounce, the emitter
sample or the BSDF sample) are the first 2^m points (2^m >= spp) of the 4-dimensional Sobol
sequence, Owen-scrambled by a hash of (the render's key, the pixel, the chunk): any
power-of-two block of them is stratified like a jittered grid in every pair of its first two
dimensions (a (0, m, 2)-net), and better than random in the rest.  The sample index is shuffled
by another nested scramble per (pixel, chunk), so that chunks do not line up with one another
(padding: sample i's camera point says nothing about its emitter point), and after the scramble
every coordinate is XORed with a hashed 32-bit digital shift, which keeps the nets and makes
each sample's coordinate exactly uniform over the 2^32 grid whatever the hash.  So every sample
is uniform on its own (the estimator stays unbiased) and a pixel's samples are stratified
together (its mean has less variance than independent samples give, most where the integrand
is smooth: penumbrae, the first bounce's cosine lobe).

The scramble is Vegdahl's hash (2021, an improvement on Laine and Karras 2011) in the
bit-reversed domain, where output bit k depends on input bits <= k only, as an Owen scramble's
flips must.  Everything is uint32 arithmetic, so the numpy code here and the compiled one
(`pathkernels.sobol_chunk`) give the same bits.  Coordinates become float32 from their top 24 bits
(as numpy's own float32 random numbers are made) and float64 as x / 2^32.
"""

from __future__ import annotations

import numpy as np

CHUNK_DIMS = 4
U32 = np.uint32
MASK32 = 0xFFFFFFFF
GOLDEN = 0x9E3779B9
SHIFT_SALT = 0x5BD1E995


def _directions() -> np.ndarray:
    """(4, 32) uint32 Sobol direction numbers (Joe and Kuo's first four dimensions: the van der
    Corput sequence, then the polynomials x + 1, x^2 + x + 1, x^3 + x + 1), bit-reversed (the
    reversed Sobol point is the XOR of the reversed directions)."""
    table = [[1 << (31 - j) for j in range(32)]]
    for s, a, m in ((1, 0, (1,)), (2, 1, (1, 3)), (3, 1, (1, 3, 1))):
        v = [m[j] << (31 - j) for j in range(s)]
        for j in range(s, 32):
            x = v[j - s] ^ (v[j - s] >> s)
            for k in range(1, s):
                x ^= ((a >> (s - 1 - k)) & 1) * v[j - k]
            v.append(x)
        table.append(v)
    return np.array([[_reverse_int(x) for x in row] for row in table], U32)


def _reverse_int(x: int) -> int:
    return int(f"{x:032b}"[::-1], 2)


REVERSED_DIRECTIONS = _directions()


def reverse_bits(x: np.ndarray) -> np.ndarray:
    """The 32 bits of each uint32 of x in reverse order."""
    x = ((x >> U32(1)) & U32(0x55555555)) | ((x & U32(0x55555555)) << U32(1))
    x = ((x >> U32(2)) & U32(0x33333333)) | ((x & U32(0x33333333)) << U32(2))
    x = ((x >> U32(4)) & U32(0x0F0F0F0F)) | ((x & U32(0x0F0F0F0F)) << U32(4))
    x = ((x >> U32(8)) & U32(0x00FF00FF)) | ((x & U32(0x00FF00FF)) << U32(8))
    return (x >> U32(16)) | (x << U32(16))


def hash32(x: np.ndarray) -> np.ndarray:
    """A well-mixing 32-bit integer hash (Wellons' lowbias32), uint32 -> uint32."""
    x = x ^ (x >> U32(16))
    x = x * U32(0x7FEB352D)
    x = x ^ (x >> U32(15))
    x = x * U32(0x846CA68B)
    return x ^ (x >> U32(16))


def owen_reversed(y: np.ndarray, seed: np.ndarray) -> np.ndarray:
    """Vegdahl's scramble of bit-reversed values y: output bit k depends on bits <= k of y and
    on the seed, a nested (Owen) scramble of the unreversed values."""
    y = y ^ (y * U32(0x3D20ADEA))
    y = y + seed
    y = y * ((seed >> U32(16)) | U32(1))
    y = y ^ (y * U32(0x05526C56))
    return y ^ (y * U32(0x53A22864))


def bits_for(spp: int) -> int:
    """m with 2^m >= spp: the Sobol points a pixel's samples are drawn from."""
    return max(int(spp - 1).bit_length(), 0)


def reversed_points(m: int) -> np.ndarray:
    """(4, 2^m) uint32: the bit-reversed first 2^m points of the 4-dimensional Sobol sequence
    (unscrambled), point j the XOR of the directions of j's bits."""
    index = np.arange(1 << m, dtype=U32)
    out = np.zeros((CHUNK_DIMS, 1 << m), U32)
    for b in range(m):
        out ^= ((index >> U32(b)) & U32(1)) * REVERSED_DIRECTIONS[:, b:b + 1]
    return out


def chunk_base(key: int, chunk: int) -> int:
    """The 32-bit value a chunk's per-pixel seeds hash from."""
    c = np.full(1, (key ^ (chunk * GOLDEN)) & MASK32, U32)
    return int(hash32(c)[0])


def chunk_bits(key: int, pixel: np.ndarray, sample: np.ndarray, chunk: int, dims: int,
               m: int) -> np.ndarray:
    """(dims, k) uint32: coordinates of sample `sample` (k,) (< 2^m) of each pixel (k,) in
    chunk `chunk`, the numpy reference of the scheme in the module docstring (and of
    `pathkernels.sobol_chunk`)."""
    with np.errstate(over="ignore"):
        seed = hash32(hash32(pixel.astype(U32) ^ U32(chunk_base(key, chunk))))
        index = reverse_bits(owen_reversed(reverse_bits(sample.astype(U32)), seed))
        index &= U32((1 << m) - 1)
        out = np.empty((dims, len(pixel)), U32)
        for d in range(dims):
            y = np.zeros(len(pixel), U32)
            for b in range(m):
                y ^= ((index >> U32(b)) & U32(1)) * REVERSED_DIRECTIONS[d, b]
            seed_d = hash32(seed + U32((d + 1) * GOLDEN & MASK32))
            shift = hash32(seed_d ^ U32(SHIFT_SALT))
            out[d] = reverse_bits(owen_reversed(y, seed_d)) ^ shift
    return out


def to_float32(x: np.ndarray) -> np.ndarray:
    """uint32 -> float32 in [0, 1) from the top 24 bits."""
    return (x >> U32(8)).astype(np.float32) * np.float32(2.0 ** -24)


def to_float64(x: np.ndarray) -> np.ndarray:
    """uint32 -> float64 in [0, 1): x / 2^32."""
    return x.astype(np.float64) * 2.0 ** -32


SAMPLERS = ("sobol", "independent")
DEFAULT_SAMPLER = "sobol"
LD_BOUNCES = 2  # bounces whose numbers are low-discrepancy (later ones: the tile's generator)


def render_key(seed: int) -> int:
    """The 32-bit key of a render's scrambles, from its seed (as the tiles' generators are:
    `numpy.random.SeedSequence`)."""
    return int(np.random.SeedSequence(seed).generate_state(1, np.uint32)[0])


class TileSamples:
    """The low-discrepancy numbers of one tile of `pathtrace.render`: its path p is sample
    p // pixels of pixel first + p % pixels (the tile's pixels row by row, spp times over).

    Chunks: 0 the camera's pixel jitter; at bounce b, 2b - 1 the emitter sample of next-event
    estimation (its point in the triangle in the first two dimensions, the triangle's choice in
    the third), 2b the BSDF sample (the cosine lobe's two numbers, the choice between mirror,
    glass and Phong, Russian roulette).  Bounces past `bounces` draw from the tile's generator
    (their share of the variance is small: the first bounce gains most).  compiled: the
    numbers from `pathkernels.sobol_chunk` (the same values)."""

    def __init__(self, key: int, first: int, pixels: int, spp: int, compiled: bool = False,
                 bounces: int = LD_BOUNCES):
        self.key, self.first, self.pixels, self.spp = key, first, pixels, spp
        self.m = bits_for(spp)
        self.bounces = bounces
        self.compiled = compiled
        if compiled:
            m = self.m
            order = reverse_bits(np.arange(1 << m, dtype=U32)) >> U32(32 - m) if m else \
                np.zeros(1, U32)
            self.table = np.ascontiguousarray(reversed_points(m)[:, order])
            self.reversed_samples = reverse_bits(np.arange(spp, dtype=U32))

    def floats(self, chunk: int, path: np.ndarray, dims: int, dim64: int = -1):
        """Paths `path` (k,) int in `chunk`: (dims, k) float32 (`to_float32`), and dimension
        dim64's float64 (`to_float64`, (k,); None where dim64 < 0)."""
        if self.compiled:
            from .pathkernels import sobol_chunk

            out = np.empty((dims, len(path)), np.float32)
            out64 = np.empty(len(path) if dim64 >= 0 else 0)
            sobol_chunk(chunk_base(self.key, chunk), self.first, self.pixels,
                        np.ascontiguousarray(path, np.int64), self.m, self.table,
                        self.reversed_samples, out, out64, dim64)
            return out, (out64 if dim64 >= 0 else None)
        path = np.asarray(path, np.int64)
        bits = chunk_bits(self.key, self.first + path % self.pixels, path // self.pixels,
                          chunk, dims, self.m)
        return to_float32(bits), (to_float64(bits[dim64]) if dim64 >= 0 else None)

    def camera(self) -> tuple[np.ndarray, np.ndarray]:
        """The pixel jitter (jx, jy) (n,) float64 of every path of the tile, in order (jy
        from 24 bits: a 2^-24 of a pixel is far below anything an image shows)."""
        u, jx = self.floats(0, np.arange(self.pixels * self.spp), 2, 0)
        return jx, u[1].astype(np.float64)

    def bounce(self, bounce: int, path: np.ndarray, scatter: bool = True, lobe: bool = True,
               roulette: bool = True):
        """The numbers of bounce `bounce` of paths `path` (k,): the emitter sample's (r float64,
        u1, u2 float32; `PathWorld.sample_emitters`) and, if scatter, the BSDF sample's (the
        lobe choice if lobe, else None; the cosine lobe's u1, u2; the roulette's if roulette,
        else None; float32), else None; or (None, None) past the low-discrepancy bounces.
        A dimension left out changes none of the others."""
        if bounce > self.bounces:
            return None, None
        light, r = self.floats(2 * bounce - 1, path, 3, 2)
        if not scatter:
            return (r, light[0], light[1]), None
        bsdf, _ = self.floats(2 * bounce, path, 4 if roulette else 3 if lobe else 2)
        return ((r, light[0], light[1]),
                (bsdf[2] if lobe else None, bsdf[0], bsdf[1], bsdf[3] if roulette else None))
