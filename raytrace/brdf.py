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

Vectors are (k, 3) float64; normals are unit and face the side the light leaves from.
"""

from __future__ import annotations

import math

import numpy as np

from .intersect import dot


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


def frame(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit tangents t, b (k, 3) with (t, b, n) orthonormal, for unit n (k, 3)
    (Duff et al. 2017, "Building an orthonormal basis, revisited": no branch, no division by 0)."""
    sign = np.where(n[:, 2] >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + n[:, 2])
    b = n[:, 0] * n[:, 1] * a
    t = np.stack([1.0 + sign * n[:, 0] ** 2 * a, sign * b, -sign * n[:, 0]], axis=1)
    s = np.stack([b, sign + n[:, 1] ** 2 * a, -n[:, 1]], axis=1)
    return t, s


def around(axis: np.ndarray, cos_theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Unit directions (k, 3) at polar angle acos(cos_theta) and azimuth phi (k,) about unit
    axes (k, 3)."""
    t, b = frame(axis)
    sin_theta = np.sqrt(np.maximum(1.0 - cos_theta ** 2, 0.0))
    return ((sin_theta * np.cos(phi))[:, None] * t + (sin_theta * np.sin(phi))[:, None] * b
            + cos_theta[:, None] * axis)


def cosine_hemisphere(rng: np.random.Generator, n: np.ndarray) -> np.ndarray:
    """Directions (k, 3) about unit normals n (k, 3) with density cos(theta) / pi."""
    u1, u2 = rng.random(len(n)), rng.random(len(n))
    return around(n, np.sqrt(1.0 - u1), 2.0 * math.pi * u2)


def mirror(wo: np.ndarray, n: np.ndarray) -> np.ndarray:
    """wo (k, 3) mirrored about n (k, 3): 2 (n·wo) n − wo (unit when wo is)."""
    return 2.0 * dot(n, wo)[:, None] * n - wo


def phong_eval(kd, ks, s, n, wo, wi) -> np.ndarray:
    """f(wo, wi) (k, 3) of the normalised Phong BRDF; kd, ks (k, 3) already normalised,
    s (k,) shininess; 0 where wi is below the surface (n·wi <= 0)."""
    cos_a = np.maximum(dot(mirror(wo, n), wi), 0.0)
    f = kd / math.pi + ks * ((s + 2.0) / (2.0 * math.pi) * cos_a ** s)[:, None]
    return np.where((dot(n, wi) > 0.0)[:, None], f, 0.0)


def phong_pdf(p_diffuse, s, n, wo, wi) -> np.ndarray:
    """(k,) solid-angle density with which `phong_sample` picks wi: the mixture
    p_d cos(theta) / pi + (1 − p_d) (s + 1) / (2 pi) cos(alpha)^s."""
    cos_t = np.maximum(dot(n, wi), 0.0)
    cos_a = np.maximum(dot(mirror(wo, n), wi), 0.0)
    return (p_diffuse * cos_t / math.pi
            + (1.0 - p_diffuse) * (s + 1.0) / (2.0 * math.pi) * cos_a ** s)


def phong_sample(rng: np.random.Generator, p_diffuse, s, n, wo) -> np.ndarray:
    """Directions wi (k, 3): the cosine lobe about n with probability p_diffuse (k,), else the
    cos^s lobe about the mirror direction of wo (which may point below the surface: the caller
    gives such samples weight 0)."""
    k = len(n)
    diffuse = rng.random(k) < p_diffuse
    wi = cosine_hemisphere(rng, n)
    g = np.flatnonzero(~diffuse)
    if len(g):
        u1, u2 = rng.random(len(g)), rng.random(len(g))
        wi[g] = around(mirror(wo[g], n[g]), u1 ** (1.0 / (s[g] + 1.0)), 2.0 * math.pi * u2)
    return wi
