"""The compiled stages of one bounce of the path tracer (`raytrace.outlook.path.pathkernels` runs
them): the BRDF per ray, the hit, next-event estimation's emitter sample and delta lights, the
bounce.

Each is the numpy path's (`raytrace.outlook.path.pathtrace`) operation for operation, in float32
(`pathstate.STATE`) where it is float32 and float64 where it is float64, with float32 constants and
no `fastmath` (see `raytrace.outlook.path.pathkernels` for why the images are then bit-identical).
Vectors are (n, 3) float32, one ray's on one cache line; tables are `pathkernels.tables`'.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .pathstate import RR_MAX_SURVIVAL, STATE_TINY

# rows of the per-triangle table (`pathkernels.tables`)
NORMAL, PLANE_D, KD, KS, SHININESS, P_DIFFUSE, GLOSSY, PHONG, REFL, TRANSP, IOR, EMITS, \
    LIGHT_PDF = 0, 3, 4, 7, 10, 11, 12, 13, 14, 15, 16, 17, 18
# rows of the per-emitter table
E_A, E_AB, E_AC, E_NORMAL, E_RADIANCE, E_PDF = 0, 3, 6, 9, 12, 15
# delta light kinds
DIRECTIONAL, POINT, SPOT, AREA = 0, 1, 2, 3
# the MIS heuristics' codes (`mis.HEURISTICS`)
POWER, BALANCE, NEE = 0, 1, 2

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


# ---- the BRDF, per ray (`raytrace.outlook.brdf`'s `_rows` kernels, operation for operation)
# ----------

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


@_jit
def _mis_weight(p_this, p_other, heuristic):
    """`mis.weight` (float32): 1 / (1 + r^beta), r = p_other / p_this; 0 where p_this is 0."""
    if not p_this > F0:
        return F0
    r = p_other / p_this
    if heuristic == POWER:
        r = r * r
    return F1 / (F1 + r)


# ---- the stages of one bounce ----------------------------------------------------------------

@_jit
def _hits(o, d, tri, path, beta, count_em, bsdf_pdf, L, background, shows_background, tab,
          tri_emission, any_emits, offset, mis, out_tri, out_path, out_beta, out_d, out_p,
          out_n, out_entering, out_start):
    """The hits of a bounce's rays, compacted in order into the out_ arrays; the background
    seen by the misses and the emission seen by the hits added to L (n_paths, 3) float64 (by
    BSDF-sampled rays: their MIS share, heuristic code mis).  Returns how many hit."""
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
            elif mis != NEE:  # found by BSDF sampling: its MIS share
                cos_y = abs(d_n)
                p_light = tab[t_i, LIGHT_PDF] * (t * t) / (cos_y if cos_y > TINY else TINY)
                w = _mis_weight(bsdf_pdf[i], p_light, mis)
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
        if mis >= 0 and mis != NEE:
            p_light = p_area * l2 / (cy if cy > TINY else TINY)
            p_bsdf = w_phong * _phong_pdf(tab, t_i, glossy_scene, n0, n1, n2, wo0, wo1, wo2,
                                          wi0, wi1, wi2, cx)
            g *= _mis_weight(p_light, p_bsdf, mis)
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
def _cosine_direction(n0, n1, n2, u1, cos_phi, sin_phi):
    """The cosine lobe's direction about n (`brdf.cosine_hemisphere_rows`), float32."""
    z = F1 - F2 * u1
    r2 = F1 - z * z
    r = np.sqrt(r2 if r2 > F0 else F0)
    w0, w1, w2 = n0 + r * cos_phi, n1 + r * sin_phi, n2 + z
    l2 = w0 * w0 + w1 * w1 + w2 * w2
    if l2 > F0:
        inv = F1 / np.sqrt(l2)
        return w0 * inv, w1 * inv, w2 * inv
    return n0, n1, n2


@_jit
def _glossy_direction(n0, n1, n2, wo0, wo1, wo2, ct, cos_phi, sin_phi):
    """The glossy lobe's direction about wo mirrored in n (`brdf.around_rows`): cos(theta) ct
    and the azimuth's cos, sin in float64, the frame in float32, the sum in float64."""
    two_dn = F2 * (n0 * wo0 + n1 * wo1 + n2 * wo2)
    a0, a1, a2 = two_dn * n0 - wo0, two_dn * n1 - wo1, two_dn * n2 - wo2
    sign = F1 if a2 >= F0 else -F1
    fa = -F1 / (sign + a2)
    fb = a0 * a1 * fa
    st2 = 1.0 - ct * ct
    st = np.sqrt(st2 if st2 > 0.0 else 0.0)
    x, y = st * cos_phi, st * sin_phi
    tx, ty, tz = F1 + sign * (a0 * a0) * fa, sign * fb, -sign * a0
    bx, by, bz = fb, sign + (a1 * a1) * fa, -a1
    w0 = np.float32(x * np.float64(tx) + y * np.float64(bx) + ct * np.float64(a0))
    w1 = np.float32(x * np.float64(ty) + y * np.float64(by) + ct * np.float64(a1))
    w2 = np.float32(x * np.float64(tz) + y * np.float64(bz) + ct * np.float64(a2))
    return w0, w1, w2


@_jit
def _glass(ior, entering, d0, d1, d2, n0, n1, n2, p0, p1, p2, offset64):
    """A glass bounce (`intersect.refract`, in float64 as there): the direction, refracted or
    (total internal reflection) mirrored, and the start offset to its side of p."""
    eta = np.float64(F1 / ior if entering else ior)
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
    o0 = np.float32(np.float64(p0) + side * np.float64(n0))
    o1 = np.float32(np.float64(p1) + side * np.float64(n1))
    o2 = np.float32(np.float64(p2) + side * np.float64(n2))
    return w0, w1, w2, o0, o1, o2


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
        if gp < n_gl and gl_index[gp] == i:  # the glossy lobe
            w0, w1, w2 = _glossy_direction(n0, n1, n2, wo0, wo1, wo2, gl_cos_theta[gp],
                                           gl_cos_phi[gp], gl_sin_phi[gp])
            gp += 1
        else:
            w0, w1, w2 = _cosine_direction(n0, n1, n2, u1[i], cos_phi[i], sin_phi[i])
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
            else:
                w0, w1, w2, o0, o1, o2 = _glass(tab[t_i, IOR], entering[i], d0, d1, d2,
                                                n0, n1, n2, p[i, 0], p[i, 1], p[i, 2],
                                                offset64)
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
