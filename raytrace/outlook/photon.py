"""Photon tracing (Jensen 1996): a caustic map and a global map, read at the eye's diffuse hits.

The lights as the path tracer sees them (`raytrace.outlook.path.pathtrace`):

* emissive triangles emit from both faces: a photon starts at a point chosen with probability
  area x mean emission (`PathWorld.sample_emitters`), on a random face, in a cosine-weighted
  direction, carrying  Phi = L_e 2 pi / (N p_A)  for N photons of the emitters;
* the delta lights keep the Whitted convention (irradiance pi · radiance · cos, no fall-off
  with distance), so a photon's power is set where it first lands, t its distance from the
  light:  Phi = pi · radiance · t^2 · Omega / N  for a point (directions uniform over
  Omega = 4 pi) or spot light (its cone), pi^2 · radiance · t^2 / N for an area light's sample
  (cosine-weighted about its normal: its cosine at the light), and pi^2 · radiance · R^2 / N for
  a directional light (a disc of radius R covering the scene).

N is the number of photons shot from that light (`share`), stored or not.  Photons are
stored at every hit with a diffuse lobe (kd > 0) after the first (the first is direct light,
which shadow rays compute: `pathtrace.next_event`), in the caustic map while every bounce
before was a mirror or glass (L S+ D), else in the global map (L .* D .* D); bounces follow
`pathtrace._scatter`, the path tracer's own lobe choice and BSDF sampling, with Russian
roulette on the Phong bounces (survival = the throughput's largest channel, at most
`RR_MAX_SURVIVAL`).

From the eye (`shade_rows`): emission seen directly or through mirrors and glass; at a hit with a
Phong lobe of weight w, direct light by shadow rays plus  w · kd / pi · E  with E the caustic map's
estimate plus the global map's (`raytrace.outlook.photonmap`), or, with a final gather, the caustic
map's plus the irradiance gathered by G cosine-weighted rays, each adding what leaves the diffuse
point it finds (direct light and both maps there; emission found is direct light or caustic at x and
is not counted again) times cos / pdf (`gather_weight`).  A glossy Phong lobe adds each photon of
both maps weighted by the lobe's BRDF toward the eye (the gather serves the diffuse part).  The path
continues through mirrors and glass as the path tracer chooses them.  Random numbers: two streams
spawned from `SeedSequence(seed)` (photons, eye), used in a fixed order, so an image depends on the
seed only.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from shadowvol.scene import AreaSample, DirectionalLight, Scene, SpotLight

from raytrace.outlook.path.pathstate import RR_MAX_SURVIVAL, STATE, PathWorld, take
from raytrace.outlook.path.pathtrace import (_delta_bounce, _scatter, _scatter_add, camera_rays,
                                             next_event)

from .brdf import cosine_hemisphere_rows, dot_rows, phong_eval_rows
from .photonmap import KERNELS, PhotonMap, kdtree

DEFAULT_PHOTONS = 200_000
DEFAULT_K = 100  # photons per density estimate (k nearest neighbours)
MAX_BOUNCES = 64  # photon bounces; Russian roulette ends paths long before
MAX_SPECULAR = 16  # mirror / glass bounces followed from the eye or a gather ray
TILE_RAYS = 1 << 15  # eye rays shaded together
LEAVING_STANDOFF = 10.0  # as `pathtrace.LEAVING_STANDOFF`


def share(power: np.ndarray, shot: int) -> np.ndarray:
    """One photon's power: its light's flux over the photons shot from that light."""
    return power / shot


def gather_weight(cos: np.ndarray, pdf: np.ndarray) -> np.ndarray:
    """A final-gather ray's weight in the irradiance integral: cos / pdf."""
    return cos / pdf


@dataclass(frozen=True)
class Estimate:
    """How the maps are read: k nearest neighbours or a fixed radius, and the kernel."""

    k: int | None = DEFAULT_K
    radius: float | None = None
    kernel: str = "cone"

    def __post_init__(self):
        if (self.k is None) == (self.radius is None):
            raise ValueError("give exactly one of k (nearest neighbours) and radius")
        if self.k is not None and (isinstance(self.k, bool) or self.k < 2):
            raise ValueError(f"k must be a whole number >= 2, got {self.k!r}")
        if self.radius is not None and not self.radius > 0.0:
            raise ValueError(f"radius must be > 0, got {self.radius!r}")
        if self.kernel not in KERNELS:
            raise ValueError(f"kernel must be one of {', '.join(KERNELS)}, got {self.kernel!r}")

    def irradiance(self, photons: PhotonMap, p: np.ndarray, n: np.ndarray,
                   brdf=None) -> np.ndarray:
        """E (3, m) float64 at points p, normals n (3, m) (brdf: `PhotonMap.irradiance`)."""
        return photons.irradiance(p.T, n.T, self.k, self.radius, self.kernel, brdf).T


@dataclass(frozen=True, eq=False)
class PhotonMaps:
    """The two maps of one photon pass; shot: photons shot, all lights together."""

    caustic: PhotonMap
    global_: PhotonMap
    shot: int


@dataclass(frozen=True, eq=False)
class PhotonImage:
    """A photon-mapped image: image (H, W, 3) float64 linear, the mean of `spp` eye samples
    per pixel; the maps; rays (eye, shadow and gather rays) and seconds of the whole render."""

    image: np.ndarray
    maps: PhotonMaps
    spp: int
    rays: int
    seconds: float


def _sources(world: PathWorld, n: int) -> list[tuple[object, int]]:
    """The lights (None: all emissive triangles) and how many of the n photons each shoots:
    shares by an estimate of power (a delta light's: pi · radiance over half the scene's
    area); the estimate's quality sets the noise, never the mean."""
    weights = []
    if len(world.emitters):
        emit = world.area[world.emitters, None] * world.emission[world.tri_object[world.emitters]]
        weights.append((None, 2.0 * math.pi * emit.mean(axis=1).sum()))
    half_area = 0.5 * world.area.sum()
    for light in world.lights:
        weights.append((light, math.pi * float(np.mean(light.radiance)) * half_area))
    total = sum(w for _, w in weights)
    if total <= 0.0:
        return []
    return [(src, max(1, round(n * w / total))) for src, w in weights if w > 0.0]


def _frame(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors (3,) completing unit axis (3,) to an orthonormal frame."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    return u, np.cross(axis, u)


def _uniform_cone(rng, k: int, axis: np.ndarray, cos_max: float) -> np.ndarray:
    """k directions (3, k) uniform in the cone of cos(theta) >= cos_max about unit axis (3,)."""
    cos_t = 1.0 - rng.random(k) * (1.0 - cos_max)
    sin_t = np.sqrt(np.maximum(1.0 - cos_t ** 2, 0.0))
    phi = 2.0 * math.pi * rng.random(k)
    u, v = _frame(axis)
    return (np.outer(u, sin_t * np.cos(phi)) + np.outer(v, sin_t * np.sin(phi))
            + np.outer(axis, cos_t))


def _from_emitters(world: PathWorld, rng, k: int):
    """k photons from the emissive triangles: starts, directions (3, k), powers (3, k)."""
    y, n_y, radiance, p_area = world.sample_emitters(rng, k)
    side = np.where(rng.random(k) < 0.5, 1.0, -1.0).astype(STATE)
    face = n_y * side
    d = cosine_hemisphere_rows(rng, np.ascontiguousarray(np.broadcast_to(face, (3, k)), STATE))
    power = share(np.broadcast_to(radiance, (3, k)) * (2.0 * math.pi / p_area), k)
    return y + world.offset * face, d, np.asarray(power, np.float64)


def _from_light(world: PathWorld, light, rng, k: int):
    """k photons from a delta light: starts, directions (3, k), powers (3, k) (times t^2 at
    the first hit unless directional: the last item, bool)."""
    radiance = np.asarray(light.radiance, np.float64)[:, None]
    if isinstance(light, DirectionalLight):  # a disc across the scene's bounding sphere
        corners = world.corners.reshape(-1, 3)
        lo, hi = corners.min(axis=0), corners.max(axis=0)
        centre, big_r = 0.5 * (lo + hi), 0.5 * float(np.linalg.norm(hi - lo)) * 1.01
        travel = np.asarray(light.direction, np.float64)
        u, v = _frame(travel)
        r, phi = big_r * np.sqrt(rng.random(k)), 2.0 * math.pi * rng.random(k)
        o = (centre - 2.0 * big_r * travel)[:, None] + np.outer(u, r * np.cos(phi)) \
            + np.outer(v, r * np.sin(phi))
        d = np.repeat(travel[:, None], k, axis=1)
        return o, d, share(radiance * math.pi ** 2 * big_r ** 2, k) * np.ones(k), False
    position = np.asarray(light.position, np.float64)
    if isinstance(light, AreaSample):
        axis = np.repeat(np.asarray(light.direction, np.float64)[:, None], k, axis=1)
        d, flux = cosine_hemisphere_rows(rng, axis), math.pi ** 2
    elif isinstance(light, SpotLight):
        d = _uniform_cone(rng, k, np.asarray(light.direction, np.float64), light.cos_cutoff)
        flux = math.pi * 2.0 * math.pi * (1.0 - light.cos_cutoff)
    else:
        d, flux = _uniform_cone(rng, k, np.array([0.0, 0.0, 1.0]), -1.0), 4.0 * math.pi ** 2
    o = np.repeat(position[:, None], k, axis=1)
    return o, d, share(radiance * flux, k) * np.ones(k), True


def emit(world: PathWorld, rng, n: int):
    """About n photons from all lights: starts, unit directions (3, k) `STATE`, powers (3, k)
    float64, and (k,) bool: the power is still to be multiplied by t^2 at the first hit."""
    parts = []
    for source, k in _sources(world, n):
        if source is None:
            o, d, power = _from_emitters(world, rng, k)
            parts.append((o, d, power, np.zeros(k, bool)))
        else:
            o, d, power, scaled = _from_light(world, source, rng, k)
            parts.append((o, d, power, np.full(k, scaled)))
    if not parts:
        return (np.zeros((3, 0), STATE),) * 2 + (np.zeros((3, 0)), np.zeros(0, bool))
    o, d, power, scaled = (np.concatenate([p[i] for p in parts], axis=-1) for i in range(4))
    return o.astype(STATE), d.astype(STATE), power, scaled


def _hit_geometry(world: PathWorld, o, d, tri):
    """The surface of hits tri (k,): surf, points p, normals n facing the ray's origin (3, k),
    entering (k,), t (k,) (as `pathtrace`'s bounce)."""
    surf = world.surface(tri)
    geo_n = surf["normal"]
    d_n = dot_rows(geo_n, d)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (surf["plane_d"] - dot_rows(geo_n, o)) / d_n
    t = np.where(np.isfinite(t), t, 0.0)
    entering = d_n < 0.0
    n = geo_n * np.where(entering, STATE(1.0), STATE(-1.0))
    return surf, o + t * d, n, entering, t


def trace_photons(world: PathWorld, rng, n: int, max_bounces: int = MAX_BOUNCES) -> dict:
    """Shoot about n photons (the module docstring); returns {"caustic", "global": (points,
    normals, powers, directions) each (m, 3), "shot": photons shot}."""
    o, d, power, scaled = emit(world, rng, n)
    shot = o.shape[1]
    stored = {"caustic": [], "global": []}
    bounced = np.zeros(shot, bool)
    diffuse = np.zeros(shot, bool)
    for bounce in range(max_bounces):
        if o.shape[1] == 0:
            break
        tri = world.closest_rows(o, d)
        h = np.flatnonzero(tri >= 0)
        o, d, tri, power, scaled, bounced, diffuse = (
            take(x, h) for x in (o, d, tri, power, scaled, bounced, diffuse))
        surf, p, nrm, entering, t = _hit_geometry(world, o, d, tri)
        if bounce == 0:
            power = power * np.where(scaled, np.asarray(t, np.float64) ** 2, 1.0)
        k = len(tri)
        diffuse_lobe = (np.broadcast_to(surf["phong"], (k,)) > 0.0) & \
            (surf["kd"].max(axis=0) > 0.0)
        store = bounced & diffuse_lobe  # (a black surface reflects nothing: no photon there)
        for name, sel in (("caustic", store & ~diffuse), ("global", store & diffuse)):
            i = np.flatnonzero(sel)
            stored[name].append((take(p, i).T, take(nrm, i).T, take(power, i).T,
                                 take(d, i).T))
        new_o = p + world.offset * nrm
        wo = -d if world.any_glossy else None
        d, factor, _, is_phong = _scatter(world, rng, surf, d, nrm, wo, entering, p, new_o)
        power = power * factor
        strongest = factor.max(axis=0)
        q = np.where(is_phong, np.minimum(strongest, RR_MAX_SURVIVAL), 1.0)
        alive = (strongest > 0.0) & (rng.random(k) < q)
        power = power / np.where(alive, q, 1.0)
        bounced = np.ones(k, bool)
        diffuse = diffuse | is_phong
        keep = np.flatnonzero(alive)
        o, d, power, scaled, bounced, diffuse = (
            take(x, keep) for x in (new_o, d, power, scaled, bounced, diffuse))
    out = {"shot": shot}
    for name, chunks in stored.items():
        out[name] = tuple(np.concatenate([c[i] for c in chunks]) if chunks else
                          np.zeros((0, 3)) for i in range(4))
    return out


def build_maps(world: PathWorld, photons: int, rng) -> PhotonMaps:
    """Trace about `photons` photons and put them into their k-d trees."""
    traced = trace_photons(world, rng, photons)
    return PhotonMaps(PhotonMap.build(*traced["caustic"]), PhotonMap.build(*traced["global"]),
                      traced["shot"])


def _final_gather(world, maps, est, p, n, rng, rays: int) -> tuple[np.ndarray, int]:
    """Irradiance (3, m) at points p, normals n (3, m) gathered by `rays` cosine-weighted rays
    each (what leaves the diffuse points they reach, `shade_rows(gather=True)`)."""
    m = p.shape[1]
    n_rep = np.repeat(n, rays, axis=1)
    wi = cosine_hemisphere_rows(rng, n_rep)
    cos = dot_rows(n_rep, wi).astype(np.float64)
    weight = np.where(cos > 0.0, gather_weight(cos, np.maximum(cos, 1e-30) / math.pi), 0.0)
    start = np.repeat(p, rays, axis=1) + world.offset * n_rep
    L, traced = shade_rows(world, maps, est, start, wi, rng, as_gather=True)
    e = (L * weight).reshape(3, m, rays).mean(axis=2)
    return e, traced + m * rays


def _photon_light(world, maps, est, surf: dict, p, n, wo, i, rng, gather: int
                  ) -> tuple[np.ndarray, int]:
    """Radiance (3, m) float64 the maps (or the caustic map and a final gather) reflect at
    hits i (m,) of a bounce (p, n, wo (3, k)), per unit throughput and Phong weight, and the
    rays traced.  The diffuse kd / pi times E; a glossy lobe weighs each photon by its BRDF
    toward wo (the final gather, cosine-weighted, serves the diffuse part only)."""
    pi, ni = take(p, i).astype(np.float64), take(n, i).astype(np.float64)
    e, rays = est.irradiance(maps.caustic, pi, ni), 0
    if gather:
        g, rays = _final_gather(world, maps, est, take(p, i), take(n, i), rng, gather)
        e += g
    else:
        e += est.irradiance(maps.global_, pi, ni)
    out = take(surf["kd"], i) * (1.0 / math.pi) * e
    if world.any_glossy:
        g = np.flatnonzero(np.isin(i, surf["glossy"]))
        if len(g):
            out[:, g] += _glossy_light(maps, est, surf, i[g], pi[:, g], ni[:, g], wo)
    return out, rays


def _glossy_light(maps, est, surf: dict, i, p, n, wo) -> np.ndarray:
    """The glossy lobe's share (3, m) of the photons' reflected radiance at hits i (m,)."""
    ks, s = take(surf["ks"], i).astype(np.float64), take(surf["shininess"], i)
    wo_i, zero = take(wo, i).astype(np.float64), np.zeros((3, len(i)))
    out = np.zeros((3, len(i)))
    for photons in (maps.caustic, maps.global_):
        def lobe(q, j, photons=photons):
            wi = -photons.direction[j].T
            return phong_eval_rows(zero[:, q], ks[:, q], s[q], n[:, q], wo_i[:, q], wi).T
        out += est.irradiance(photons, p, n, lobe)
    return out


def shade_rows(world: PathWorld, maps: PhotonMaps, est: Estimate, o, d, rng,
               gather: int = 0, as_gather: bool = False, light_samples: int = 1
               ) -> tuple[np.ndarray, int]:
    """Radiance (3, k) float64 along rays o, d (3, k) and the rays traced (the module
    docstring).  gather: final-gather rays per diffuse hit (0: read the global map there);
    as_gather: these are gather rays (no emission, no background, no further gather, one
    light sample); light_samples: the direct light's shadow rays to the emitters per hit,
    averaged (delta lights: each is one exact ray anyway)."""
    o, d = np.asarray(o, STATE), np.asarray(d, STATE)
    L = np.zeros((3, o.shape[1]))
    background = np.asarray(world.scene.background, np.float64)[:, None]
    path = np.arange(o.shape[1])
    beta = np.ones(o.shape, STATE)
    rays = 0
    for _ in range(MAX_SPECULAR + 1):
        tri = world.closest_rows(o, d)
        rays += len(tri)
        if not as_gather and background.any():
            miss = np.flatnonzero(tri < 0)
            _scatter_add(L, take(path, miss), take(beta, miss) * background)
        h = np.flatnonzero(tri >= 0)
        if len(h) == 0:
            break
        o, d, tri, path, beta = (take(x, h) for x in (o, d, tri, path, beta))
        surf, p, n, entering, _ = _hit_geometry(world, o, d, tri)
        k = len(tri)
        if world.any_emits and not as_gather:
            e = np.flatnonzero(surf["emits"])
            _scatter_add(L, take(path, e), take(beta, e) * take(world.tri_emission, take(tri, e)))
        start = p + world.offset * n
        wo = -d if world.any_glossy else None
        shots = light_samples if len(world.emitters) and not as_gather else 1
        for _ in range(shots):
            direct, shadow = next_event(world, rng, p, n, wo, surf, beta, start, mis=False)
            rays += shadow
            _scatter_add(L, path, direct / shots)
        phong = np.broadcast_to(surf["phong"], (k,))
        i = np.flatnonzero(phong > 0.0)
        if len(i):
            reflected, traced = _photon_light(world, maps, est, surf, p, n, wo, i, rng,
                                              0 if as_gather else gather)
            rays += traced
            _scatter_add(L, take(path, i), take(beta, i) * take(phong, i) * reflected)
        if not world.any_delta:
            break
        u = rng.random(k, dtype=STATE)
        is_mirror = u < surf["refl"]
        is_glass = ~is_mirror & (u < surf["refl"] + surf["transp"])
        new_d = d.copy()
        _delta_bounce(world, d, n, entering, surf, p, is_mirror, is_glass, start, new_d)
        go = np.flatnonzero(is_mirror | is_glass)
        o, d, path, beta = (take(x, go) for x in (start, new_d, path, beta))
    return L, rays


def radiance_leaving(world: PathWorld, maps: PhotonMaps, est: Estimate, points, normals, rng,
                     gather: int = 0) -> tuple[np.ndarray, int]:
    """Radiance (k, 3) leaving surface points (k, 3) along their unit normals (k, 3), as
    `pathtrace.radiance_leaving` looks at them (a ray from just in front, back along -normal)."""
    start = np.asarray(points) + LEAVING_STANDOFF * world.offset * np.asarray(normals)
    L, rays = shade_rows(world, maps, est, start.T, -np.asarray(normals).T, rng, gather)
    return np.ascontiguousarray(L.T), rays


def render(scene: Scene, photons: int = DEFAULT_PHOTONS, estimate: Estimate = Estimate(),
           spp: int = 4, gather: int = 0, seed: int = 0, backend: str = "embree",
           jitter: bool = True, light_samples: int = 1) -> PhotonImage:
    """Photon-map `scene`: about `photons` photons, then `spp` eye rays per pixel (jittered
    in the pixel, or at its centre: jitter False), `gather` final-gather rays per diffuse hit
    (0: none), `light_samples` shadow rays to the emitters per diffuse hit for the direct
    light.  The image depends on the arguments only (`seed`: the module docstring)."""
    for name, value, low in (("photons", photons, 1), ("spp", spp, 1), ("gather", gather, 0),
                             ("light_samples", light_samples, 1)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
            raise ValueError(f"{name} must be a whole number >= {low}, got {value!r}")
    kdtree()  # a missing scipy fails here, before any photon is traced
    start = time.perf_counter()
    photon_seq, eye_seq = np.random.SeedSequence(seed).spawn(2)
    world = PathWorld(scene, backend)
    maps = build_maps(world, photons, np.random.default_rng(photon_seq))
    rng = np.random.default_rng(eye_seq)
    H, W = scene.height, scene.width
    row = np.tile(np.repeat(np.arange(H), W), spp)  # the pixels, spp times over
    col = np.tile(np.arange(W), H * spp)
    total, rays = np.zeros((3, H * W)), 0
    for s in range(0, len(row), TILE_RAYS):
        part = slice(s, s + TILE_RAYS)
        o, d = camera_rays(scene.camera, W, H, row[part], col[part], rng if jitter else None)
        L, traced = shade_rows(world, maps, estimate, o, d, rng, gather,
                               light_samples=light_samples)
        pixel = row[part] * W + col[part]
        for c in range(3):
            total[c] += np.bincount(pixel, L[c], minlength=H * W)
        rays += traced
    image = (total / spp).T.reshape(H, W, 3)
    return PhotonImage(image, maps, spp, rays, time.perf_counter() - start)
