"""The path tracer's per-bounce shading compiled with numba (the optional `fast` extra).

`trace_rows` here is `raytrace.outlook.path.pathtrace.trace_rows` with the numpy stages between the
Embree calls replaced by a few `@njit` loops over the rays of a bounce
(`raytrace.outlook.path.pathstages`): the hit (compaction to the hits, surface gather, hit point,
emission seen and its MIS share), the emitter sample of next-event estimation (its shadow rays, then
its shading), each delta light's shadow rays and shading, and the bounce (BSDF sample, delta
bounces, Russian roulette, compaction to the survivors).  Embree still traces each bounce's closest
hits and each group of shadow rays as one batch, through `PathWorld.closest_rows` / `occluded_rows`.

Same estimator, same random numbers, same arithmetic.  The random numbers are drawn in numpy,
from the same generator, in the same order and dtypes as the numpy path, and handed to the
kernels; so are the transcendental functions of them (the azimuths' cos and sin, the glossy
lobe's u^(1/(s+1))), because numpy's SIMD versions and the C library's, which compiled code
calls, may differ in the last bit.  The kernels do each float32 (`STATE`) / float64 operation
of the numpy path in its order and precision (float32 constants, no `fastmath`, so LLVM neither
reassociates nor contracts to FMA).  The image is then bit-identical to the numpy path's where
no power is taken (Lambertian, mirror and glass materials, every kind of light: the Cornell box,
the furnace); the glossy lobe's cos^s is the one power computed in a kernel (libm's powf where
numpy uses its SIMD power), so a glossy scene agrees to float32 rounding, and where that
rounding flips a Russian-roulette choice a path differs (tests/raytrace/outlook/test_pathkernels.py
states the budget).  `camera_rays` is `pathtrace.camera_rays` compiled, bit-identical too.

Kernels release the GIL (`nogil`), so `pathtrace.render`'s tiles run on its thread pool;
`cache=True` keeps the compiled code under $NUMBA_CACHE_DIR where that is set, else next to the
kernels' files, else in numba's user-wide cache directory, whichever is writable first; where
none is (numba then refuses `cache=True`), they compile in every process.
"""

from __future__ import annotations

import math
import threading

import numpy as np

from .mis import code
from .pathstages import (  # (numba: an ImportError here where it is missing)
    AREA,
    DIRECTIONAL,
    GLOSSY,
    P_DIFFUSE,
    POINT,
    SHININESS,
    SPOT,
    _add_direct,
    _bounce,
    _emitter_rays,
    _emitter_shade,
    _hits,
    _jit,
    _light_add,
    _light_rays,
)
from .pathstate import STATE


def _f32(rows) -> np.ndarray:
    """Rows (n,) or (m, n) stacked into one contiguous (n, P) float32 table, one line per item,
    each converted as `pathstate.pack` converts them (float64 first), so the values are the
    numpy path's."""
    return np.ascontiguousarray(np.concatenate(
        [np.atleast_2d(np.asarray(v, np.float64)).astype(STATE) for v in rows]).T)


def tables(world) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The kernels' tables of a `pathstate.PathWorld`: per triangle (M, 19) float32, every
    column (NORMAL ... LIGHT_PDF) whatever the scene needs, its emission (M, 3) float32, and per
    emitter (E, 16) float32: what a hit needs on one or two cache lines."""
    cached = getattr(world, "_kernel_tables", None)
    if cached is not None:
        return cached
    ob = world.tri_object
    tri = _f32([world.tracer.normals.T, world.tracer.plane_d, world.kd[ob].T, world.ks[ob].T,
                world.shininess[ob], world.p_diffuse[ob], world.ks[ob].max(axis=1) > 0.0,
                1.0 - world.refl[ob] - world.transp[ob], world.refl[ob], world.transp[ob],
                world.ior[ob], world.tri_emits, world.light_pdf_area])
    e = world.emitters
    c = world.corners[e]
    em = _f32([c[:, 0].T, (c[:, 1] - c[:, 0]).T, (c[:, 2] - c[:, 0]).T,
               world.tracer.normals[e].T, world.emission[world.tri_object][e].T,
               world.emitter_prob / world.area[e] if len(e) else np.zeros(0)]) \
        if len(e) else np.zeros((0, 16), STATE)
    world._kernel_tables = (tri, np.ascontiguousarray(world.tri_emission.T), em)
    return world._kernel_tables


@_jit
def _camera(eye, right, up, back, near, fx, fy, cx, cy, width, row0, rows, spp, jx, jy, o, d):
    """`pathtrace.camera_rays` for a tile's pixels (rows row0 .. row0 + rows, every column,
    spp times over, as `pathtrace.render` orders them) into o, d (n, 3) float64; jx, jy (n,)
    the jitter (0.5: the centres)."""
    i = 0  # the ray of (row, col) in sample s: the order of `pathtrace.render`'s tiles
    for _ in range(spp):
        for row in range(row0, row0 + rows):
            for col in range(width):
                sx = (col + jx[i] - cx) / fx
                sy = (cy - (row + jy[i])) / fy
                v0 = sx * right[0] + sy * up[0] - back[0]
                v1 = sx * right[1] + sy * up[1] - back[1]
                v2 = sx * right[2] + sy * up[2] - back[2]
                o[i, 0] = eye[0] + near * v0
                o[i, 1] = eye[1] + near * v1
                o[i, 2] = eye[2] + near * v2
                length = np.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
                d[i, 0], d[i, 1], d[i, 2] = v0 / length, v1 / length, v2 / length
                i += 1


def camera_rays(camera, width: int, height: int, rows: slice, spp: int,
                rng: np.random.Generator | None, jitter=None) -> tuple[np.ndarray, np.ndarray]:
    """`pathtrace.camera_rays` of the pixels of rows `rows`, every column, `spp` times over
    (the order `pathtrace.render` traces them): the same random numbers (or the jitter
    (jx, jy) given), the same rays, origins and directions (3, n) float64 (views of (n, 3)
    arrays)."""
    from raytrace.camera import camera_basis, pixel_focal

    right, up, back = camera_basis(camera)
    fx, fy, cx, cy = pixel_focal(camera, width, height)
    n = (rows.stop - rows.start) * width * spp
    if jitter is not None:
        jx, jy = (np.ascontiguousarray(j, np.float64) for j in jitter)
    else:
        jx = rng.random(n) if rng is not None else np.full(n, 0.5)
        jy = rng.random(n) if rng is not None else np.full(n, 0.5)
    o, d = np.empty((n, 3)), np.empty((n, 3))  # rows of (3, n) would alias in the cache
    _camera(np.asarray(camera.eye, np.float64), right, up, back, float(camera.near),
            fx, fy, cx, cy, width, rows.start, rows.stop - rows.start, spp, jx, jy, o, d)
    return o.T, d.T


# ---- the path loop ---------------------------------------------------------------------------

def _lights(world) -> list[tuple]:
    """The delta lights as the kernels take them: (light, kind, position, direction (3,)
    float32, cos_cutoff float32, pi x radiance (3,) float32, tmax of its shadow rays)."""
    from shadowvol.scene import AreaSample, DirectionalLight, SpotLight

    out = []
    for light in world.lights:
        zero = np.zeros(3, STATE)
        if isinstance(light, DirectionalLight):
            kind, pos, direction, tmax = DIRECTIONAL, zero, light.direction, None
        else:
            kind = AREA if isinstance(light, AreaSample) else \
                SPOT if isinstance(light, SpotLight) else POINT
            pos, tmax = light.position, 1.0
            direction = light.direction if kind != POINT else zero
        cutoff = STATE(light.cos_cutoff) if kind in (SPOT, AREA) else STATE(0.0)
        out.append((kind, np.asarray(pos, STATE), np.asarray(direction, STATE), cutoff,
                    math.pi * np.asarray(light.radiance, STATE), tmax))
    return out


class _Buffers:
    """Every array the path loop needs, allocated once for n rays (fresh large arrays each
    bounce cost a page fault per 4 KiB on first touch, as much as the kernels themselves);
    a bounce uses the first k rows.  The rays' state is double-buffered: `state` in, `spare`
    out, swapped after each bounce.  `buffers` keeps one set per thread for its next tile."""

    def __init__(self, n: int):
        self.size = n

        def state():
            return [np.empty((n, 3), STATE), np.empty((n, 3), STATE), np.empty(n, np.int64),
                    np.empty((n, 3), STATE), np.empty(n, np.bool_), np.empty(n, STATE)]

        self.state, self.spare = state(), state()  # o, d, path, beta, count_em, bsdf_pdf
        self.tri, self.path = np.empty(n, np.int64), np.empty(n, np.int64)
        self.beta, self.d, self.p, self.n, self.start, self.direct, self.wi, self.so, \
            self.sd = (np.empty((n, 3), STATE) for _ in range(9))
        self.entering = np.empty(n, np.bool_)
        self.cos_x, self.cos_y, self.dist2, self.u1, self.u2, self.u3, self.u4 = \
            (np.empty(n, STATE) for _ in range(7))
        self.r = np.empty(n)
        self.cand, self.jem = np.empty(n, np.int64), np.empty(n, np.int64)


def buffers(world, n: int) -> _Buffers:
    """This thread's buffers for n rays, kept on `world` for the thread's next tile (the tiles
    of `pathtrace.render` run one at a time on each thread of its pool)."""
    pool = world.__dict__.setdefault("_kernel_buffers", {})
    b = pool.get(threading.get_ident())
    if b is None or b.size < n:
        b = pool[threading.get_ident()] = _Buffers(n)
    return b


def _next_event(world, rng, b: _Buffers, k: int, tab, etab, cdf, lights, offset,
                mis: int, u_light) -> int:
    """Next-event estimation at the k hits of a bounce into b.direct (zero on entry): one
    emitter sample each (its random numbers those of `PathWorld.sample_emitters`, or u_light (r, u1,
    u2) given), then every delta light; mis: the heuristic's code (`raytrace.outlook.path.mis`), -1
    for none.  Returns the shadow rays traced."""
    glossy, delta = world.any_glossy, world.any_delta
    direct, rays = b.direct, 0
    if len(world.emitters) > 0:
        if u_light is None:
            rng.random(out=b.r[:k])
            rng.random(dtype=STATE, out=b.u1[:k])
            rng.random(dtype=STATE, out=b.u2[:k])
        else:
            b.r[:k], b.u1[:k], b.u2[:k] = u_light
        m = _emitter_rays(k, b.p, b.n, b.start, b.tri, tab, etab, cdf, b.r, b.u1, b.u2,
                          offset, b.wi, b.cos_x, b.cos_y, b.dist2, b.jem, b.cand, b.so, b.sd)
        blocked = world.occluded_rows(b.so[:m].T, b.sd[:m].T, 1.0)
        rays += m
        _emitter_shade(direct, b.beta, b.tri, tab, etab, b.n, b.d, b.jem, b.wi, b.cos_x,
                       b.cos_y, b.dist2, b.cand, blocked, m, mis, glossy, delta)
    for kind, pos, direction, cutoff, pi_radiance, tmax in lights:
        m = _light_rays(k, kind, pos, direction, cutoff, b.p, b.n, b.start, b.tri, tab,
                        delta, b.wi, b.cos_x, b.cos_y, b.cand, b.so, b.sd)
        blocked = world.occluded_rows(b.so[:m].T, b.sd[:m].T, tmax)
        rays += m
        _light_add(direct, b.beta, b.tri, tab, b.n, b.d, b.wi, b.cos_x, b.cos_y, b.cand,
                   blocked, m, pi_radiance, kind == AREA, glossy, delta)
    return rays


def _bounce_randoms(rng, b: _Buffers, k: int, tab, delta: bool, glossy: bool, roulette: bool,
                    u_bsdf=None):
    """The random numbers of a bounce, in the numpy path's order, into b.u3 (the delta
    choice), b.u1, b.u4 (roulette), or those of u_bsdf (`sobol.TileSamples.bounce`); returns
    the azimuths' cos, sin (k,) float32 and the glossy lobe's (gl_index, cos_theta, cos_phi,
    sin_phi) of the vertices that sample it."""
    no_f64 = np.zeros(0)
    phi = b.u2[:k]
    if u_bsdf is not None:
        b.u1[:k], phi[:] = u_bsdf[1:3]
        if delta:
            b.u3[:k] = u_bsdf[0]
        if roulette:
            b.u4[:k] = u_bsdf[3]
    if delta and u_bsdf is None:
        rng.random(dtype=STATE, out=b.u3[:k])
    if u_bsdf is None:
        rng.random(dtype=STATE, out=b.u1[:k])
        rng.random(dtype=STATE, out=phi)
    phi *= np.float32(2.0 * math.pi)  # as numpy's float32 product, in place
    cos_phi, sin_phi = np.cos(phi, out=b.cos_x[:k]), np.sin(phi, out=b.cos_y[:k])
    lobe = (np.zeros(0, np.int64), no_f64, no_f64, no_f64)
    if glossy:
        candidates = np.flatnonzero(np.take(tab[:, GLOSSY], b.tri[:k]) > 0.0)
        if len(candidates):
            tc = np.take(b.tri, candidates)
            gl_index = candidates[rng.random(len(candidates)) >= np.take(tab[:, P_DIFFUSE], tc)]
            if len(gl_index):
                gu1, gu2 = rng.random(len(gl_index)), rng.random(len(gl_index))
                s = np.take(tab[:, SHININESS], np.take(b.tri, gl_index))
                gl_phi = 2.0 * math.pi * gu2
                lobe = (gl_index, gu1 ** (1.0 / (s + 1.0)), np.cos(gl_phi), np.sin(gl_phi))
            else:
                lobe = (gl_index,) + lobe[1:]
    if roulette and u_bsdf is None:
        rng.random(dtype=STATE, out=b.u4[:k])
    return cos_phi, sin_phi, lobe


def trace_rows(world, o: np.ndarray, d: np.ndarray, rng: np.random.Generator,
               max_depth: int, rr_start: int, heuristic: str = "power", samples=None
               ) -> tuple[np.ndarray, int]:
    """`raytrace.outlook.path.pathtrace.trace_rows` (same arguments, same result) with compiled
    shading. The kernels' vectors are (n, 3) float32, one ray's on one cache line: rows of (3, n)
    arrays, 2^15 apart in a tile, alias in the cache and made them twice as slow.  They write
    compacted rays into the first rows of whole buffers and are told how many are valid (every array
    stays C-contiguous: one compiled version each)."""
    tab, tri_emission, etab = tables(world)
    mis = code(heuristic)
    lights = _lights(world)
    offset = STATE(world.offset)
    glossy, delta, emits = world.any_glossy, world.any_delta, world.any_emits
    cdf = np.ascontiguousarray(world.emitter_cdf, np.float64)
    n = np.shape(o)[1]  # rays in flight: the first n rows of the state
    b = buffers(world, n)
    rays_o, rays_d, path, beta, count_em, bsdf_pdf = b.state
    rays_o[:n] = np.asarray(o).T
    rays_d[:n] = np.asarray(d).T
    path[:n] = np.arange(n)
    beta[:n] = 1.0
    count_em[:n] = True
    bsdf_pdf[:n] = 0.0
    L = np.zeros((n, 3))
    background = np.ascontiguousarray(world.scene.background, np.float64)
    shows_background = bool(background.any())
    rays = 0
    for bounce in range(1, max_depth + 1):
        rays_o, rays_d, path, beta, count_em, bsdf_pdf = b.state
        tri = world.closest_rows(rays_o[:n].T, rays_d[:n].T)
        rays += n
        k = _hits(rays_o, rays_d, tri, path, beta, count_em, bsdf_pdf, L, background,
                  shows_background, tab, tri_emission, emits, offset, mis, b.tri, b.path,
                  b.beta, b.d, b.p, b.n, b.entering, b.start)
        if k == 0:
            break
        direct = b.direct
        direct[:k] = 0.0
        u_light, u_bsdf = (None, None) if samples is None else \
            samples.bounce(bounce, b.path[:k], bounce < max_depth, delta, bounce >= rr_start)
        rays += _next_event(world, rng, b, k, tab, etab, cdf, lights, offset,
                            mis if bounce < max_depth else -1, u_light)
        if bounce == max_depth:
            _add_direct(L, b.path, direct, k)
            break
        roulette = bounce >= rr_start
        cos_phi, sin_phi, lobe = _bounce_randoms(rng, b, k, tab, delta, glossy, roulette,
                                                 u_bsdf)
        out = b.spare
        n = _bounce(k, L, direct, b.tri, b.path, b.beta, b.d, b.p, b.n, b.entering, b.start,
                    tab, glossy, delta, b.u3, b.u1, cos_phi, sin_phi, *lobe, roulette, b.u4,
                    float(world.offset), *out)
        b.state, b.spare = b.spare, b.state
        if n == 0:
            break
    return np.ascontiguousarray(L.T), rays


# ---- the low-discrepancy numbers (`raytrace.outlook.path.sobol`, bit for bit, in uint64 masked to
# 32) ----

M32 = np.uint64(0xFFFFFFFF)
U1, U8, U15, U16 = np.uint64(1), np.uint64(8), np.uint64(15), np.uint64(16)


@_jit
def _hash32(x):
    x ^= x >> U16
    x = (x * np.uint64(0x7FEB352D)) & M32
    x ^= x >> U15
    x = (x * np.uint64(0x846CA68B)) & M32
    return x ^ (x >> U16)


@_jit
def _reverse32(x):
    x = ((x >> U1) & np.uint64(0x55555555)) | ((x & np.uint64(0x55555555)) << U1)
    x = ((x >> np.uint64(2)) & np.uint64(0x33333333)) | \
        ((x & np.uint64(0x33333333)) << np.uint64(2))
    x = ((x >> np.uint64(4)) & np.uint64(0x0F0F0F0F)) | \
        ((x & np.uint64(0x0F0F0F0F)) << np.uint64(4))
    x = ((x >> U8) & np.uint64(0x00FF00FF)) | ((x & np.uint64(0x00FF00FF)) << U8)
    return ((x >> U16) | (x << U16)) & M32


@_jit
def _owen_reversed(y, seed):
    y ^= (y * np.uint64(0x3D20ADEA)) & M32
    y = (y + seed) & M32
    y = (y * ((seed >> U16) | U1)) & M32
    y ^= (y * np.uint64(0x05526C56)) & M32
    return y ^ ((y * np.uint64(0x53A22864)) & M32)


@_jit
def sobol_chunk(base, first, pixels, path, m, table, reversed_samples, out, out64, dim64):
    """`sobol.chunk_bits` of paths `path` (k,) int64 of a tile (`sobol.TileSamples`) as
    float32 (`sobol.to_float32`) into out (dims, k), and dimension dim64 as float64
    (`sobol.to_float64`) into out64 (k,) (where dim64 >= 0).  base: `sobol.chunk_base` of the
    chunk; table (4, 2^m) uint32: the bit-reversed Sobol points (`sobol.reversed_points`) in
    the order of their m-bit-reversed index; reversed_samples: the bit-reversed sample
    indices."""
    dims = out.shape[0]
    low = np.uint64(32 - m)
    b64 = np.uint64(base)
    # each pixel's seeds: the index scramble's, then per dimension the scramble's and the shift
    seeds = np.empty((pixels, 1 + 2 * dims), np.uint64)
    for q in range(pixels):
        seed = _hash32(_hash32((np.uint64(first + q) & M32) ^ b64))
        seeds[q, 0] = seed
        for d in range(dims):
            seed_d = _hash32((seed + np.uint64((d + 1) * 0x9E3779B9 & 0xFFFFFFFF)) & M32)
            seeds[q, 1 + d] = seed_d
            seeds[q, 1 + dims + d] = _hash32(seed_d ^ np.uint64(0x5BD1E995))
    inv = 1.0 / pixels
    for i in range(path.shape[0]):
        p = path[i]
        sample = np.int64(p * inv)  # p // pixels without a division (p < 2^52)
        if sample * pixels > p:
            sample -= 1
        elif (sample + 1) * pixels <= p:
            sample += 1
        q = p - sample * pixels
        # the scrambled index, bit-reversed: its top m bits are the index's, reversed
        j = _owen_reversed(np.uint64(reversed_samples[sample]), seeds[q, 0]) >> low
        for d in range(dims):
            x = _reverse32(_owen_reversed(np.uint64(table[d, j]), seeds[q, 1 + d])) \
                ^ seeds[q, 1 + dims + d]
            out[d, i] = np.float32(x >> U8) * np.float32(2.0 ** -24)
            if d == dim64:
                out64[i] = np.float64(x) * 2.0 ** -32
