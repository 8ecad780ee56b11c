"""The path tracer's per-bounce shading compiled with numba (the optional `fast` extra).

`trace_rows` here is `raytrace.pathtrace.trace_rows` with the numpy stages between the Embree
calls replaced by a few `@njit` loops over the rays of a bounce: the hit (compaction to the hits,
surface gather, hit point, emission seen and its MIS share), the emitter sample of next-event
estimation (its shadow rays, then its shading), each delta light's shadow rays and shading, and
the bounce (BSDF sample, delta bounces, Russian roulette, compaction to the survivors).  Embree
still traces each bounce's closest hits and each group of shadow rays as one batch, through
`PathWorld.closest_rows` / `occluded_rows`.

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
rounding flips a Russian-roulette choice a path differs (tests/raytrace/test_pathkernels.py
states the budget).  `camera_rays` is `pathtrace.camera_rays` compiled, bit-identical too.

Kernels release the GIL (`nogil`), so `pathtrace.render`'s tiles run on its thread pool;
`cache=True` keeps the compiled code under $NUMBA_CACHE_DIR where that is set, else next to
this file, else in numba's user-wide cache directory, whichever is writable first; where none
is (numba then refuses `cache=True`), they compile in every process.
"""

from __future__ import annotations

import math
import threading

import numba
import numpy as np

from .pathstate import RR_MAX_SURVIVAL, STATE, STATE_TINY

# rows of the per-triangle table (`tables`)
NORMAL, PLANE_D, KD, KS, SHININESS, P_DIFFUSE, GLOSSY, PHONG, REFL, TRANSP, IOR, EMITS, \
    LIGHT_PDF = 0, 3, 4, 7, 10, 11, 12, 13, 14, 15, 16, 17, 18
# rows of the per-emitter table
E_A, E_AB, E_AC, E_NORMAL, E_RADIANCE, E_PDF = 0, 3, 6, 9, 12, 15
# delta light kinds
DIRECTIONAL, POINT, SPOT, AREA = 0, 1, 2, 3

F0, F1, F2 = np.float32(0.0), np.float32(1.0), np.float32(2.0)
INV_PI = np.float32(1.0 / math.pi)
INV_2PI_DENOM = np.float32(2.0 * math.pi)  # divided by, as numpy divides by the float32 of it
TINY = np.float32(STATE_TINY)
RR_MAX = np.float32(RR_MAX_SURVIVAL)


def _jit(fn):
    """njit, releasing the GIL, cached on disk where numba finds a writable cache directory
    (numba refuses `cache=True` with a RuntimeError where it finds none)."""
    try:
        return numba.njit(cache=True, nogil=True, error_model="numpy")(fn)
    except RuntimeError:
        return numba.njit(nogil=True, error_model="numpy")(fn)


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


# ---- the BRDF, per ray (`raytrace.brdf`'s `_rows` kernels, operation for operation) ----------

@_jit
def _cos_alpha(tab, t, n0, n1, n2, wo0, wo1, wo2, wi0, wi1, wi2):
    """max(r . wi, 0), r = wo mirrored about n (`brdf.mirror_rows`)."""
    two_dn = F2 * (n0 * wo0 + n1 * wo1 + n2 * wo2)
    c = (two_dn * n0 - wo0) * wi0 + (two_dn * n1 - wo1) * wi1 + (two_dn * n2 - wo2) * wi2
    return c if c > F0 else F0


@_jit
def _phong_f(tab, t, glossy_scene, n0, n1, n2, wo0, wo1, wo2, wi0, wi1, wi2, cos_t):
    """`brdf.phong_eval_rows` for one ray: f (3 float32)."""
    f0, f1, f2 = tab[t, KD] * INV_PI, tab[t, KD + 1] * INV_PI, tab[t, KD + 2] * INV_PI
    if glossy_scene and tab[t, GLOSSY] > F0:
        ss = tab[t, SHININESS]
        c = (ss + F2) / INV_2PI_DENOM * \
            _cos_alpha(tab, t, n0, n1, n2, wo0, wo1, wo2, wi0, wi1, wi2) ** ss
        f0 = f0 + tab[t, KS] * c
        f1 = f1 + tab[t, KS + 1] * c
        f2 = f2 + tab[t, KS + 2] * c
    if not cos_t > F0:
        return F0 * f0, F0 * f1, F0 * f2
    return f0, f1, f2


@_jit
def _phong_pdf(tab, t, glossy_scene, n0, n1, n2, wo0, wo1, wo2, wi0, wi1, wi2, cos_t):
    """`brdf.phong_pdf_rows` for one ray (float32)."""
    p_d = tab[t, P_DIFFUSE]
    pdf = p_d * (cos_t if cos_t > F0 else F0) * INV_PI
    if glossy_scene and tab[t, GLOSSY] > F0:
        ss = tab[t, SHININESS]
        pdf = pdf + (F1 - p_d) * (ss + F1) / INV_2PI_DENOM * \
            _cos_alpha(tab, t, n0, n1, n2, wo0, wo1, wo2, wi0, wi1, wi2) ** ss
    return pdf


# ---- the stages of one bounce ----------------------------------------------------------------

@_jit
def _hits(o, d, tri, path, beta, count_em, bsdf_pdf, L, background, shows_background, tab,
          tri_emission, any_emits, offset, out_tri, out_path, out_beta, out_d, out_p, out_n,
          out_entering, out_start):
    """The hits of a bounce's rays, compacted in order into the out_ arrays; the background
    seen by the misses and the emission seen by the hits added to L (n_paths, 3) float64.
    Returns how many hit."""
    k = 0
    for i in range(tri.shape[0]):
        t_i = tri[i]
        q = path[i]
        if t_i < 0:
            if shows_background and count_em[i]:
                for c in range(3):
                    L[q, c] += np.float64(beta[i, c]) * background[c]
            continue
        g0, g1, g2 = tab[t_i, NORMAL], tab[t_i, NORMAL + 1], tab[t_i, NORMAL + 2]
        d0, d1, d2 = d[i, 0], d[i, 1], d[i, 2]
        d_n = g0 * d0 + g1 * d1 + g2 * d2
        t = (tab[t_i, PLANE_D] - (g0 * o[i, 0] + g1 * o[i, 1] + g2 * o[i, 2])) / d_n
        if not np.isfinite(t):
            t = F0
        entering = d_n < F0
        sign = F1 if entering else -F1
        for c in range(3):
            p_c = o[i, c] + t * d[i, c]
            n_c = tab[t_i, NORMAL + c] * sign
            out_p[k, c] = p_c
            out_n[k, c] = n_c
            out_start[k, c] = p_c + offset * n_c
            out_d[k, c] = d[i, c]
            out_beta[k, c] = beta[i, c]
        out_entering[k] = entering
        out_tri[k] = t_i
        out_path[k] = q
        if any_emits and tab[t_i, EMITS] > F0:
            if count_em[i]:
                for c in range(3):
                    L[q, c] += np.float64(beta[i, c] * tri_emission[t_i, c])
            else:  # found by BSDF sampling: its MIS share
                cos_y = abs(d_n)
                p_light = tab[t_i, LIGHT_PDF] * (t * t) / (cos_y if cos_y > TINY else TINY)
                pe = bsdf_pdf[i]
                w = pe / (pe + p_light)
                for c in range(3):
                    L[q, c] += np.float64(beta[i, c] * tri_emission[t_i, c] * w)
        k += 1
    return k


@_jit
def _emitter_rays(k, p, n, start, tri, tab, etab, cdf, r, u1, u2, offset, wi, cos_x, cos_y,
                  dist2, jem, cand, so, sd):
    """One point on the emitters per vertex (`PathWorld.sample_emitters`, its random numbers r
    (k,) float64, u1, u2 (k,) float32): wi, cos_x, cos_y, dist2, the emitter jem, and the
    shadow rays (so, sd (m, 3), as `pathtrace.next_event` casts them) of the candidates cand.
    Returns m."""
    n_e = cdf.shape[0]
    m = 0
    for i in range(k):
        lo, hi = 0, n_e  # np.searchsorted(cdf, r, side="right")
        while lo < hi:
            mid = (lo + hi) // 2
            if cdf[mid] <= r[i]:
                lo = mid + 1
            else:
                hi = mid
        j = min(lo, n_e - 1)
        jem[i] = j
        rr = np.sqrt(u1[i])
        a = rr * (F1 - u2[i])
        b = rr * u2[i]
        y0 = etab[j, E_A] + a * etab[j, E_AB] + b * etab[j, E_AC]
        y1 = etab[j, E_A + 1] + a * etab[j, E_AB + 1] + b * etab[j, E_AC + 1]
        y2 = etab[j, E_A + 2] + a * etab[j, E_AB + 2] + b * etab[j, E_AC + 2]
        t0, t1, t2 = y0 - p[i, 0], y1 - p[i, 1], y2 - p[i, 2]
        l2 = t0 * t0 + t1 * t1 + t2 * t2
        inv = F1 / np.sqrt(l2 if l2 > TINY else TINY)
        w0, w1, w2 = t0 * inv, t1 * inv, t2 * inv
        cx = n[i, 0] * w0 + n[i, 1] * w1 + n[i, 2] * w2
        ny0, ny1, ny2 = etab[j, E_NORMAL], etab[j, E_NORMAL + 1], etab[j, E_NORMAL + 2]
        cy = -(ny0 * w0 + ny1 * w1 + ny2 * w2)
        side = offset if cy >= F0 else -offset
        cy = abs(cy)
        wi[i, 0], wi[i, 1], wi[i, 2] = w0, w1, w2
        cos_x[i], cos_y[i], dist2[i] = cx, cy, l2
        if cx > F0 and cy > F0 and tab[tri[i], PHONG] > F0 and l2 > F0:
            cand[m] = i
            so[m, 0], so[m, 1], so[m, 2] = start[i, 0], start[i, 1], start[i, 2]
            sd[m, 0] = y0 + side * ny0 - start[i, 0]
            sd[m, 1] = y1 + side * ny1 - start[i, 1]
            sd[m, 2] = y2 + side * ny2 - start[i, 2]
            m += 1
    return m


@_jit
def _emitter_shade(direct, beta, tri, tab, etab, n, d, jem, wi, cos_x, cos_y, dist2, cand,
                   blocked, m, mis, glossy_scene, delta_scene):
    """The emitter sample's contribution (`pathtrace.next_event`) into direct (k, 3) (zero on
    entry) for the unblocked candidates."""
    for idx in range(m):
        if blocked[idx]:
            continue
        i = cand[idx]
        t_i, j = tri[i], jem[i]
        cx, cy, l2 = cos_x[i], cos_y[i], dist2[i]
        p_area = etab[j, E_PDF]
        n0, n1, n2 = n[i, 0], n[i, 1], n[i, 2]
        wo0, wo1, wo2 = -d[i, 0], -d[i, 1], -d[i, 2]
        wi0, wi1, wi2 = wi[i, 0], wi[i, 1], wi[i, 2]
        w_phong = tab[t_i, PHONG] if delta_scene else F1
        g = cx * cy / (l2 * p_area)
        if mis:
            p_light = p_area * l2 / cy
            p_bsdf = w_phong * _phong_pdf(tab, t_i, glossy_scene, n0, n1, n2, wo0, wo1, wo2,
                                          wi0, wi1, wi2, cx)
            g *= p_light / (p_light + p_bsdf)
        g = g * w_phong
        if glossy_scene:
            f0, f1, f2 = _phong_f(tab, t_i, glossy_scene, n0, n1, n2, wo0, wo1, wo2,
                                  wi0, wi1, wi2, cx)
            direct[i, 0] = beta[i, 0] * f0 * etab[j, E_RADIANCE] * g
            direct[i, 1] = beta[i, 1] * f1 * etab[j, E_RADIANCE + 1] * g
            direct[i, 2] = beta[i, 2] * f2 * etab[j, E_RADIANCE + 2] * g
        else:  # Lambert: f = kd / pi
            gl = g * INV_PI
            for c in range(3):
                direct[i, c] = beta[i, c] * tab[t_i, KD + c] * etab[j, E_RADIANCE + c] * gl


@_jit
def _light_rays(k, kind, position, direction, cos_cutoff, p, n, start, tri, tab, delta_scene,
                wi, cos_x, cos_light, cand, so, sd):
    """A delta light's directions wi, cosines and the shadow rays (so, sd (m, 3)) of its
    candidates cand (`pathtrace.next_event`).  Returns m."""
    m = 0
    for i in range(k):
        if kind == DIRECTIONAL:
            w0, w1, w2 = -direction[0], -direction[1], -direction[2]
        else:
            t0 = position[0] - p[i, 0]
            t1 = position[1] - p[i, 1]
            t2 = position[2] - p[i, 2]
            inv = F1 / np.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
            w0, w1, w2 = t0 * inv, t1 * inv, t2 * inv
        cx = n[i, 0] * w0 + n[i, 1] * w1 + n[i, 2] * w2
        w_phong = tab[tri[i], PHONG] if delta_scene else F1
        ok = cx > F0 and w_phong > F0
        cl = F0
        if kind == SPOT or kind == AREA:
            cl = -(w0 * direction[0] + w1 * direction[1] + w2 * direction[2])
            ok = ok and cl >= cos_cutoff
        wi[i, 0], wi[i, 1], wi[i, 2] = w0, w1, w2
        cos_x[i], cos_light[i] = cx, cl
        if ok:
            cand[m] = i
            for c in range(3):
                so[m, c] = start[i, c]
                sd[m, c] = wi[i, c] if kind == DIRECTIONAL else position[c] - start[i, c]
            m += 1
    return m


@_jit
def _light_add(direct, beta, tri, tab, n, d, wi, cos_x, cos_light, cand, blocked, m,
               pi_radiance, is_area, glossy_scene, delta_scene):
    """A delta light's contribution added into direct (k, 3) for its unblocked candidates."""
    for idx in range(m):
        if blocked[idx]:
            continue
        i = cand[idx]
        t_i = tri[i]
        cx = cos_x[i]
        f0, f1, f2 = _phong_f(tab, t_i, glossy_scene, n[i, 0], n[i, 1], n[i, 2],
                              -d[i, 0], -d[i, 1], -d[i, 2], wi[i, 0], wi[i, 1], wi[i, 2], cx)
        g = (tab[t_i, PHONG] if delta_scene else F1) * cx
        if is_area:
            cl = cos_light[i]
            g *= cl if cl > F0 else F0
        direct[i, 0] += beta[i, 0] * f0 * pi_radiance[0] * g
        direct[i, 1] += beta[i, 1] * f1 * pi_radiance[1] * g
        direct[i, 2] += beta[i, 2] * f2 * pi_radiance[2] * g


@_jit
def _add_direct(L, path, direct, k):
    for i in range(k):
        for c in range(3):
            L[path[i], c] += np.float64(direct[i, c])


@_jit
def _reflect(d0, d1, d2, n0, n1, n2):
    """`intersect.reflect` in float32: d - 2 (n.d) n."""
    two = F2 * (n0 * d0 + n1 * d1 + n2 * d2)
    return d0 - two * n0, d1 - two * n1, d2 - two * n2


@_jit
def _bounce(k, L, direct, tri, path, beta, d, p, n, entering, start, tab, glossy_scene,
            delta_scene, u_delta, u1, cos_phi, sin_phi, gl_index, gl_cos_theta, gl_cos_phi,
            gl_sin_phi, roulette, u_rr, offset64, out_o, out_d, out_path, out_beta,
            out_count_em, out_pdf):
    """Add direct (k, 3) into L, then the next direction of every path (`pathtrace.trace_rows`:
    BSDF sample, the mirror and glass bounces, Russian roulette with u_rr), the survivors
    compacted in order into the out_ arrays.  gl_index (g,) the sorted vertices that sample the
    glossy lobe, with its cos(theta) and the azimuth's cos, sin (float64).  Returns how many
    survive."""
    count = 0
    gp = 0
    n_gl = gl_index.shape[0]
    for i in range(k):
        q = path[i]
        for c in range(3):
            L[q, c] += np.float64(direct[i, c])
        t_i = tri[i]
        n0, n1, n2 = n[i, 0], n[i, 1], n[i, 2]
        d0, d1, d2 = d[i, 0], d[i, 1], d[i, 2]
        wo0, wo1, wo2 = -d0, -d1, -d2
        is_mirror = is_glass = False
        if delta_scene:
            u = u_delta[i]
            is_mirror = u < tab[t_i, REFL]
            is_glass = not is_mirror and u < tab[t_i, REFL] + tab[t_i, TRANSP]
        is_phong = not is_mirror and not is_glass
        # the cosine lobe (`brdf.cosine_hemisphere_rows`)
        z = F1 - F2 * u1[i]
        r2 = F1 - z * z
        r = np.sqrt(r2 if r2 > F0 else F0)
        w0, w1, w2 = n0 + r * cos_phi[i], n1 + r * sin_phi[i], n2 + z
        l2 = w0 * w0 + w1 * w1 + w2 * w2
        if l2 > F0:
            inv = F1 / np.sqrt(l2)
            w0, w1, w2 = w0 * inv, w1 * inv, w2 * inv
        else:
            w0, w1, w2 = n0, n1, n2
        if gp < n_gl and gl_index[gp] == i:  # the glossy lobe (`brdf.around_rows`)
            two_dn = F2 * (n0 * wo0 + n1 * wo1 + n2 * wo2)
            a0, a1, a2 = two_dn * n0 - wo0, two_dn * n1 - wo1, two_dn * n2 - wo2
            sign = F1 if a2 >= F0 else -F1
            fa = -F1 / (sign + a2)
            fb = a0 * a1 * fa
            ct = gl_cos_theta[gp]
            st2 = 1.0 - ct * ct
            st = np.sqrt(st2 if st2 > 0.0 else 0.0)
            x, y = st * gl_cos_phi[gp], st * gl_sin_phi[gp]
            tx, ty, tz = F1 + sign * (a0 * a0) * fa, sign * fb, -sign * a0
            bx, by, bz = fb, sign + (a1 * a1) * fa, -a1
            w0 = np.float32(x * np.float64(tx) + y * np.float64(bx) + ct * np.float64(a0))
            w1 = np.float32(x * np.float64(ty) + y * np.float64(by) + ct * np.float64(a1))
            w2 = np.float32(x * np.float64(tz) + y * np.float64(bz) + ct * np.float64(a2))
            gp += 1
        cos = n0 * w0 + n1 * w1 + n2 * w2
        pdf = _phong_pdf(tab, t_i, glossy_scene, n0, n1, n2, wo0, wo1, wo2, w0, w1, w2, cos)
        if glossy_scene:
            f0, f1, f2 = _phong_f(tab, t_i, glossy_scene, n0, n1, n2, wo0, wo1, wo2,
                                  w0, w1, w2, cos)
            s = cos / pdf if cos > F0 and pdf > F0 else F0
            fac0, fac1, fac2 = f0 * s, f1 * s, f2 * s
        elif pdf > F0:
            fac0, fac1, fac2 = tab[t_i, KD], tab[t_i, KD + 1], tab[t_i, KD + 2]
        else:
            fac0, fac1, fac2 = tab[t_i, KD] * F0, tab[t_i, KD + 1] * F0, tab[t_i, KD + 2] * F0
        pdf_next = (tab[t_i, PHONG] if delta_scene else F1) * pdf
        o0, o1, o2 = start[i, 0], start[i, 1], start[i, 2]
        if not is_phong:
            fac0 = fac1 = fac2 = F1
            pdf_next = F0
            if is_mirror:
                w0, w1, w2 = _reflect(d0, d1, d2, n0, n1, n2)
            else:  # glass (`intersect.refract`, in float64 as there)
                ior = tab[t_i, IOR]
                eta = np.float64(F1 / ior if entering[i] else ior)
                cos1 = -(n0 * d0 + n1 * d1 + n2 * d2)
                kk = 1.0 - eta * eta * np.float64(F1 - cos1 * cos1)
                if kk < 0.0:  # total internal reflection
                    w0, w1, w2 = _reflect(d0, d1, d2, n0, n1, n2)
                    side = offset64
                else:
                    s = eta * np.float64(cos1) - np.sqrt(kk)
                    w0 = np.float32(eta * np.float64(d0) + s * np.float64(n0))
                    w1 = np.float32(eta * np.float64(d1) + s * np.float64(n1))
                    w2 = np.float32(eta * np.float64(d2) + s * np.float64(n2))
                    side = -offset64
                o0 = np.float32(np.float64(p[i, 0]) + side * np.float64(n0))
                o1 = np.float32(np.float64(p[i, 1]) + side * np.float64(n1))
                o2 = np.float32(np.float64(p[i, 2]) + side * np.float64(n2))
        b0, b1, b2 = beta[i, 0] * fac0, beta[i, 1] * fac1, beta[i, 2] * fac2
        strongest = max(max(b0, b1), b2)
        alive = strongest > F0
        if roulette:
            survive = strongest if strongest < RR_MAX else RR_MAX
            alive = alive and u_rr[i] < survive
            if alive:
                inv = F1 / survive
                b0, b1, b2 = b0 * inv, b1 * inv, b2 * inv
        if not alive:
            continue
        out_o[count, 0], out_o[count, 1], out_o[count, 2] = o0, o1, o2
        out_d[count, 0], out_d[count, 1], out_d[count, 2] = w0, w1, w2
        out_beta[count, 0], out_beta[count, 1], out_beta[count, 2] = b0, b1, b2
        out_path[count] = q
        out_count_em[count] = not is_phong
        out_pdf[count] = pdf_next
        count += 1
    return count


@_jit
def _camera(eye, right, up, back, near, half_w, half_h, width, height, row0, rows, spp, jx, jy,
            o, d):
    """`pathtrace.camera_rays` for a tile's pixels (rows row0 .. row0 + rows, every column,
    spp times over, as `pathtrace.render` orders them) into o, d (n, 3) float64; jx, jy (n,)
    the jitter (0.5: the centres)."""
    i = 0  # the ray of (row, col) in sample s: the order of `pathtrace.render`'s tiles
    for _ in range(spp):
        for row in range(row0, row0 + rows):
            for col in range(width):
                sx = ((col + jx[i]) / width * 2.0 - 1.0) * half_w
                sy = (1.0 - (row + jy[i]) / height * 2.0) * half_h
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
                rng: np.random.Generator | None) -> tuple[np.ndarray, np.ndarray]:
    """`pathtrace.camera_rays` of the pixels of rows `rows`, every column, `spp` times over
    (the order `pathtrace.render` traces them): the same random numbers, the same rays,
    origins and directions (3, n) float64 (views of (n, 3) arrays)."""
    from .camera import camera_basis

    right, up, back = camera_basis(camera)
    n = (rows.stop - rows.start) * width * spp
    jx = rng.random(n) if rng is not None else np.full(n, 0.5)
    jy = rng.random(n) if rng is not None else np.full(n, 0.5)
    half_h = math.tan(math.radians(camera.fov_y) / 2.0)
    o, d = np.empty((n, 3)), np.empty((n, 3))  # rows of (3, n) would alias in the cache
    _camera(np.asarray(camera.eye, np.float64), right, up, back, float(camera.near),
            half_h * width / height, half_h, width, height, rows.start,
            rows.stop - rows.start, spp, jx, jy, o, d)
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


def trace_rows(world, o: np.ndarray, d: np.ndarray, rng: np.random.Generator,
               max_depth: int, rr_start: int) -> tuple[np.ndarray, int]:
    """`raytrace.pathtrace.trace_rows` (same arguments, same result) with compiled shading.
    The kernels' vectors are (n, 3) float32, one ray's on one cache line: rows of (3, n)
    arrays, 2^15 apart in a tile, alias in the cache and made them twice as slow.  They write
    compacted rays into the first rows of whole buffers and are told how many are valid (every
    array stays C-contiguous: one compiled version each)."""
    tab, tri_emission, etab = tables(world)
    lights = _lights(world)
    offset = STATE(world.offset)
    glossy, delta, emits = world.any_glossy, world.any_delta, world.any_emits
    has_emitters = len(world.emitters) > 0
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
    no_f64, no_int = np.zeros(0), np.zeros(0, np.int64)
    rays = 0
    for bounce in range(1, max_depth + 1):
        rays_o, rays_d, path, beta, count_em, bsdf_pdf = b.state
        tri = world.closest_rows(rays_o[:n].T, rays_d[:n].T)
        rays += n
        k = _hits(rays_o, rays_d, tri, path, beta, count_em, bsdf_pdf, L, background,
                  shows_background, tab, tri_emission, emits, offset, b.tri, b.path, b.beta,
                  b.d, b.p, b.n, b.entering, b.start)
        if k == 0:
            break
        direct = b.direct
        direct[:k] = 0.0
        if has_emitters:  # the random numbers of `PathWorld.sample_emitters`
            rng.random(out=b.r[:k])
            rng.random(dtype=STATE, out=b.u1[:k])
            rng.random(dtype=STATE, out=b.u2[:k])
            m = _emitter_rays(k, b.p, b.n, b.start, b.tri, tab, etab, cdf, b.r, b.u1, b.u2,
                              offset, b.wi, b.cos_x, b.cos_y, b.dist2, b.jem, b.cand, b.so, b.sd)
            blocked = world.occluded_rows(b.so[:m].T, b.sd[:m].T, 1.0)
            rays += m
            _emitter_shade(direct, b.beta, b.tri, tab, etab, b.n, b.d, b.jem, b.wi, b.cos_x,
                           b.cos_y, b.dist2, b.cand, blocked, m, bounce < max_depth, glossy,
                           delta)
        for kind, pos, direction, cutoff, pi_radiance, tmax in lights:
            m = _light_rays(k, kind, pos, direction, cutoff, b.p, b.n, b.start, b.tri, tab,
                            delta, b.wi, b.cos_x, b.cos_y, b.cand, b.so, b.sd)
            blocked = world.occluded_rows(b.so[:m].T, b.sd[:m].T, tmax)
            rays += m
            _light_add(direct, b.beta, b.tri, tab, b.n, b.d, b.wi, b.cos_x, b.cos_y, b.cand,
                       blocked, m, pi_radiance, kind == AREA, glossy, delta)
        if bounce == max_depth:
            _add_direct(L, b.path, direct, k)
            break
        # the random numbers of the bounce, in the numpy path's order
        if delta:
            rng.random(dtype=STATE, out=b.u3[:k])
        rng.random(dtype=STATE, out=b.u1[:k])
        phi = b.u2[:k]
        rng.random(dtype=STATE, out=phi)
        phi *= np.float32(2.0 * math.pi)  # as numpy's float32 product, in place
        cos_phi, sin_phi = np.cos(phi, out=b.cos_x[:k]), np.sin(phi, out=b.cos_y[:k])
        gl_index, gl_cos_theta, gl_cos_phi, gl_sin_phi = no_int, no_f64, no_f64, no_f64
        if glossy:
            candidates = np.flatnonzero(np.take(tab[:, GLOSSY], b.tri[:k]) > 0.0)
            if len(candidates):
                tc = np.take(b.tri, candidates)
                lobe = rng.random(len(candidates)) >= np.take(tab[:, P_DIFFUSE], tc)
                gl_index = candidates[lobe]
                if len(gl_index):
                    gu1, gu2 = rng.random(len(gl_index)), rng.random(len(gl_index))
                    s = np.take(tab[:, SHININESS], np.take(b.tri, gl_index))
                    gl_cos_theta = gu1 ** (1.0 / (s + 1.0))
                    gl_phi = 2.0 * math.pi * gu2
                    gl_cos_phi, gl_sin_phi = np.cos(gl_phi), np.sin(gl_phi)
        roulette = bounce >= rr_start
        if roulette:
            rng.random(dtype=STATE, out=b.u4[:k])
        out = b.spare
        n = _bounce(k, L, direct, b.tri, b.path, b.beta, b.d, b.p, b.n, b.entering, b.start,
                    tab, glossy, delta, b.u3, b.u1, cos_phi, sin_phi, gl_index, gl_cos_theta,
                    gl_cos_phi, gl_sin_phi, roulette, b.u4, float(world.offset), *out)
        b.state, b.spare = b.spare, b.state
        if n == 0:
            break
    return np.ascontiguousarray(L.T), rays
