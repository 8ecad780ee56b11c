"""The reflection model of the path tracer and radiosity: Lambert plus energy-conserving Phong,
and the delta lobes (mirror, glass) with the Whitted tracer's weights.

A material (`shadowvol.scene.Material`) scatters light three ways, chosen with the weights the
Whitted tracer gives them: with probability `reflectivity` a perfect mirror, with probability
`transparency` refraction (no Fresnel term, as in Whitted; radiance is not scaled by eta^2), and
otherwise the glossy-diffuse Phong BRDF

    f(wo, wi) = kd / pi  +  ks (s + 2) / (2 pi) · max(r · wi, 0)^s,      r = wo mirrored about n

(the "modified Phong" of Lafortune & Willems 1994, s the shininess).  The (s + 2) / (2 pi)
normalisation makes the glossy lobe's directional albedo at most ks for every wo, so the BRDF
conserves energy when kd + ks <= 1 in every channel; materials written for Whitted often have
kd + ks > 1, and `normalised_phong` then scales kd and ks by the same factor 1 / max(kd + ks).
`scene.ambient` and `Material.ambient` are not part of it: ambient light is local illumination's
stand-in for the indirect light that these integrators compute.

Normals are unit and face the side the light leaves from.  Two layouts of the same functions:
the public ones take vectors as (k, 3) float64 (the rest of `raytrace`); the path tracer's
kernels, suffixed `_rows`, take them as (3, k) float64, one contiguous row per coordinate:
numpy's loops over a last axis of length 3 (gathers, masks, broadcasts of (k, 1)) run several
times slower than over rows of length k, and a per-row loop releases the GIL for the thread
pool.  The (k, 3) functions are the `_rows` kernels on transposed copies.
"""

from __future__ import annotations

import math

import numpy as np


def normalised_phong(kd: np.ndarray, ks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """kd, ks (K, 3) scaled so that kd + ks <= 1 in every channel (one factor per material,
    1 / max over channels of kd + ks, only where that exceeds 1)."""
    total = (kd + ks).max(axis=1, keepdims=True)
    scale = np.where(total > 1.0, 1.0 / np.maximum(total, 1e-300), 1.0)
    return kd * scale, ks * scale


def diffuse_probability(kd: np.ndarray, ks: np.ndarray) -> np.ndarray:
    """(K,) probability of sampling the diffuse lobe rather than the glossy one: mean(kd) /
    (mean(kd) + mean(ks)), 1 where both are zero (nothing to sample; the weight is 0 anyway)."""
    d, s = kd.mean(axis=1), ks.mean(axis=1)
    return np.where(d + s > 0.0, d / np.maximum(d + s, 1e-300), 1.0)


def dot_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot products (k,) of vectors a, b (3, k)."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _rows(v: np.ndarray) -> np.ndarray:
    """(k, 3) -> (3, k) contiguous, and back: (3, k) -> (k, 3)."""
    return np.ascontiguousarray(np.asarray(v, dtype=np.float64).T)


def frame_rows(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit tangents t, b (3, k) with (t, b, n) orthonormal, for unit n (3, k)
    (Duff et al. 2017, "Building an orthonormal basis, revisited": no branch, no division by 0)."""
    sign = np.where(n[2] >= 0.0, n.dtype.type(1.0), n.dtype.type(-1.0))
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    t = np.stack([1.0 + sign * n[0] ** 2 * a, sign * b, -sign * n[0]])
    s = np.stack([b, sign + n[1] ** 2 * a, -n[1]])
    return t, s


def frame(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`frame_rows` for n (k, 3): tangents (k, 3)."""
    t, s = frame_rows(_rows(n))
    return _rows(t), _rows(s)


def around_rows(axis: np.ndarray, cos_theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Unit directions (3, k) at polar angle acos(cos_theta) and azimuth phi (k,) about unit
    axes (3, k)."""
    t, b = frame_rows(axis)
    sin_theta = np.sqrt(np.maximum(1.0 - cos_theta * cos_theta, 0.0))
    x, y = sin_theta * np.cos(phi), sin_theta * np.sin(phi)
    return x * t + y * b + cos_theta * axis


def around(axis: np.ndarray, cos_theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """`around_rows` for axes (k, 3): directions (k, 3)."""
    return _rows(around_rows(_rows(axis), np.asarray(cos_theta), np.asarray(phi)))


def cosine_hemisphere_rows(rng: np.random.Generator, n: np.ndarray, u=None) -> np.ndarray:
    """Directions (3, k) about unit normals n (3, k) with density cos(theta) / pi: n plus a
    uniform point of the unit sphere, normalised (the unit sphere through the origin centred on
    n, seen from the origin: uniform area there is density cos(theta) / pi; no tangent frame).
    The measure-zero case n + s = 0 gives n.  The azimuth's cosine and sine are float32
    (numpy's float64 sin and cos are ~20 times slower): the direction moves by ~1e-7 rad, far
    below any image's noise; the rest is float64.  u: the two uniforms (u1 of n's dtype, u2
    float32, (k,) each) instead of drawing them from rng."""
    k = n.shape[1]
    if u is None:
        u1 = rng.random(k, dtype=n.dtype if n.dtype == np.float32 else np.float64)
        u2 = rng.random(k, dtype=np.float32)
    else:
        u1, u2 = u
    z = 1.0 - 2.0 * u1
    r = np.sqrt(np.maximum(1.0 - z * z, 0.0))
    phi = np.float32(2.0 * math.pi) * u2
    w = np.stack([n[0] + r * np.cos(phi), n[1] + r * np.sin(phi), n[2] + z])
    length2 = dot_rows(w, w)
    ok = length2 > 0.0
    w *= 1.0 / np.sqrt(np.where(ok, length2, 1.0))
    return np.where(ok, w, n)


def cosine_hemisphere(rng: np.random.Generator, n: np.ndarray) -> np.ndarray:
    """Directions (k, 3) about unit normals n (k, 3) with density cos(theta) / pi (by a
    tangent frame, `around`: radiosity's form-factor rays)."""
    u1, u2 = rng.random(len(n)), rng.random(len(n))
    return around(n, np.sqrt(1.0 - u1), 2.0 * math.pi * u2)


def mirror_rows(wo: np.ndarray, n: np.ndarray) -> np.ndarray:
    """wo (3, k) mirrored about n (3, k): 2 (n·wo) n − wo (unit when wo is)."""
    return 2.0 * dot_rows(n, wo) * n - wo


def mirror(wo: np.ndarray, n: np.ndarray) -> np.ndarray:
    """wo (k, 3) mirrored about n (k, 3): 2 (n·wo) n − wo (unit when wo is)."""
    return _rows(mirror_rows(_rows(wo), _rows(n)))


def _subset(glossy):
    """The gather of the glossy entries: everything (None) or columns `glossy` (m,) int."""
    if glossy is None:
        return lambda a: a
    return lambda a: np.take(a, glossy, axis=-1)


def phong_eval_rows(kd, ks, s, n, wo, wi, glossy=None, cos_t=None) -> np.ndarray:
    """f(wo, wi) (3, k) of the normalised Phong BRDF; kd, ks (3, k) already normalised,
    s (k,) shininess, n, wo, wi (3, k); 0 where wi is below the surface (n·wi <= 0).
    glossy : None, or the indices (m,) of the only entries whose ks may be non-zero (the glossy
    lobe is evaluated there only);  cos_t : n·wi (k,) if the caller has it."""
    f = kd * (1.0 / math.pi)
    if glossy is None or len(glossy):
        sub = _subset(glossy)
        cos_a = np.maximum(dot_rows(mirror_rows(sub(wo), sub(n)), sub(wi)), 0.0)
        ss = sub(s)
        lobe = sub(ks) * ((ss + 2.0) / (2.0 * math.pi) * cos_a ** ss)
        if glossy is None:
            f = f + lobe
        else:
            f[:, glossy] += lobe
    if cos_t is None:
        cos_t = dot_rows(n, wi)
    return f * (cos_t > 0.0)  # f is finite: a product, cheaper than np.where


def phong_eval(kd, ks, s, n, wo, wi) -> np.ndarray:
    """f(wo, wi) (k, 3) of the normalised Phong BRDF; kd, ks (k, 3) already normalised,
    s (k,) shininess; 0 where wi is below the surface (n·wi <= 0)."""
    return _rows(phong_eval_rows(_rows(kd), _rows(ks), np.asarray(s, np.float64), _rows(n),
                                 _rows(wo), _rows(wi)))


def phong_pdf_rows(p_diffuse, s, n, wo, wi, glossy=None, cos_t=None) -> np.ndarray:
    """(k,) solid-angle density with which `phong_sample_rows` picks wi (3, k): the mixture
    p_d cos(theta) / pi + (1 − p_d) (s + 1) / (2 pi) cos(alpha)^s.  glossy, cos_t: as for
    `phong_eval_rows` (outside `glossy`, p_d must be 1)."""
    if cos_t is None:
        cos_t = dot_rows(n, wi)
    pdf = p_diffuse * np.maximum(cos_t, 0.0) * (1.0 / math.pi)
    if glossy is None or len(glossy):
        sub = _subset(glossy)
        cos_a = np.maximum(dot_rows(mirror_rows(sub(wo), sub(n)), sub(wi)), 0.0)
        ss = sub(s)
        lobe = (1.0 - sub(p_diffuse)) * (ss + 1.0) / (2.0 * math.pi) * cos_a ** ss
        if glossy is None:
            pdf = pdf + lobe
        else:
            pdf[glossy] += lobe
    return pdf


def phong_pdf(p_diffuse, s, n, wo, wi) -> np.ndarray:
    """(k,) solid-angle density with which `phong_sample` picks wi: the mixture
    p_d cos(theta) / pi + (1 − p_d) (s + 1) / (2 pi) cos(alpha)^s."""
    return phong_pdf_rows(np.asarray(p_diffuse, np.float64), np.asarray(s, np.float64),
                          _rows(n), _rows(wo), _rows(wi))


def phong_sample_rows(rng: np.random.Generator, p_diffuse, s, n, wo, glossy=None, u=None
                      ) -> np.ndarray:
    """Directions wi (3, k): the cosine lobe about n (3, k) with probability p_diffuse (k,),
    else the cos^s lobe about the mirror direction of wo (3, k) (which may point below the
    surface: the caller gives such samples weight 0).  glossy : None, or the indices (m,) of the
    only entries whose p_diffuse may be below 1 (the lobe is chosen by a random number there
    only).  u: the cosine lobe's two uniforms (`cosine_hemisphere_rows`); the glossy lobe's
    are drawn from rng."""
    sub = _subset(glossy)
    wi = cosine_hemisphere_rows(rng, n, u)
    if glossy is None or len(glossy):
        cand = np.arange(n.shape[1]) if glossy is None else glossy
        g = cand[rng.random(len(cand)) >= sub(p_diffuse)]
        if len(g):
            u1, u2 = rng.random(len(g)), rng.random(len(g))
            axis = mirror_rows(np.take(wo, g, axis=1), np.take(n, g, axis=1))
            wi[:, g] = around_rows(axis, u1 ** (1.0 / (s[g] + 1.0)), 2.0 * math.pi * u2)
    return wi


def phong_sample(rng: np.random.Generator, p_diffuse, s, n, wo) -> np.ndarray:
    """Directions wi (k, 3): the cosine lobe about n with probability p_diffuse (k,), else the
    cos^s lobe about the mirror direction of wo (which may point below the surface: the caller
    gives such samples weight 0)."""
    return _rows(phong_sample_rows(rng, np.asarray(p_diffuse, np.float64),
                                   np.asarray(s, np.float64), _rows(n), _rows(wo)))
