"""Unidirectional path tracing (Kajiya 1986) with next-event estimation, vectorised per bounce.

The estimator, for every path vertex x reached from the eye (all rays of one bounce traced at
once, per tile, like `raytrace.whitted`):

* emission seen directly: a camera ray, or a ray leaving a mirror / glass (delta) bounce, adds
  the radiance `Material.emission` of what it hits;
* next-event estimation at every non-delta vertex: one point y on the emissive triangles, chosen
  with probability proportional to area x mean emitted radiance and uniformly within the
  triangle, adds  f(wo, wi) L_e cos_x cos_y / (|x − y|^2 p_A(y))  if the segment is unblocked;
  each point / spot / directional light of `scene.lights` adds  f · pi · radiance · cos_x
  (these delta lights keep the Whitted convention: irradiance pi · radiance · n·l, no distance
  fall-off, so a Lambertian surface gets kd · radiance · n·l as in Whitted);
* the next direction is drawn from the material (`raytrace.brdf`); emission found by a ray drawn
  from the Phong lobes is added too, and the two estimates of the same light are combined by
  multiple importance sampling (Veach 1995, balance heuristic: NEE weighs its sample by
  p_light / (p_light + p_bsdf), the BSDF-sampled hit by p_bsdf / (p_light + p_bsdf), both
  densities in solid angle).  MIS, not plain NEE: with NEE alone a point next to a large emitter
  (a corner of the furnace box) gets 1/r^2 spikes; the BSDF sample covers them;
* Russian roulette from bounce `RR_START_BOUNCE` on: a path survives with probability
  q = min(max_channel(throughput), RR_MAX_SURVIVAL) and its throughput is divided by q.

`max_depth` is the number of bounces light may make between an emitter and the eye: 1 is direct
lighting (emission seen + NEE at the first hit), the default `DEFAULT_MAX_DEPTH` is deep enough
that the truncation is below the noise (Russian roulette ends paths long before).  A ray that
escapes shows `scene.background` to the camera and through delta bounces; the background does not
light the scene.  `scene.ambient` is ignored (the integrator computes what ambient fakes).

Every object is traced as its triangles (spheres as their icospheres), so the emitter that NEE
samples is exactly the surface that rays hit.  Random numbers: one `numpy` generator per tile,
spawned from `SeedSequence(seed)`, so an image depends on the seed only (not on the threads).
"""

from __future__ import annotations

import math
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from shadowvol.scene import DirectionalLight, Scene, SpotLight

from .backends import cpu_threads, make_backend
from .brdf import (
    diffuse_probability,
    normalised_phong,
    phong_eval,
    phong_pdf,
    phong_sample,
)
from .camera import camera_basis
from .intersect import dot, reflect, refract
from .progress import Progress
from .tolerances import surface_offset

RR_START_BOUNCE = 3  # Russian roulette from the third bounce on
RR_MAX_SURVIVAL = 0.95  # never certain survival: bounds the expected path length
DEFAULT_MAX_DEPTH = 64  # bounces; the truncation bias is below rho^64 of the image
TILE_PATHS = 1 << 16  # paths traced together: bounds memory, sets the progress step
LEAVING_STANDOFF = 10.0  # `radiance_leaving` starts its rays this many surface offsets out


class PathWorld:
    """The scene as the path tracer and radiosity see it: all objects' triangles in one backend,
    per-object material arrays, and the emitters to sample.

    tri_object : (M,) int, the object of each triangle;  area : (M,) float64
    kd, ks : (K, 3) normalised Phong (`brdf.normalised_phong`);  shininess, refl, transp, ior,
    p_diffuse : (K,);  emission : (K, 3)
    emitters : (E,) int, emissive triangles;  emitter_cdf : (E,) float64, cumulative choice
    probability (area x mean emission)
    """

    def __init__(self, scene: Scene, backend: str = "embree", parallel: bool = True):
        self.scene = scene
        self.parallel = parallel
        vertices, faces, self.tri_object = scene.triangles()
        self.tracer = make_backend(backend, vertices, faces)
        self.corners = vertices[faces]  # (M, 3, 3)
        cross = np.cross(self.corners[:, 1] - self.corners[:, 0],
                         self.corners[:, 2] - self.corners[:, 0])
        self.area = 0.5 * np.linalg.norm(cross, axis=1)
        self.offset = surface_offset(scene)
        m = [o.material for o in scene.objects]
        self.kd, self.ks = normalised_phong(np.array([x.diffuse for x in m]),
                                            np.array([x.specular for x in m]))
        self.shininess = np.array([x.shininess for x in m])
        self.refl = np.array([x.reflectivity for x in m])
        self.transp = np.array([x.transparency for x in m])
        self.ior = np.array([x.ior for x in m])
        self.emission = np.array([x.emission for x in m])
        self.p_diffuse = diffuse_probability(self.kd, self.ks)
        power = self.area * self.emission[self.tri_object].mean(axis=1)
        self.emitters = np.flatnonzero(power > 0.0)
        self.emitter_cdf = np.cumsum(power[self.emitters]) / max(power.sum(), 1e-300)
        self.emitter_prob = power[self.emitters] / max(power.sum(), 1e-300)
        # p_A(y) of `sample_emitters` for a point on each triangle (0 off the emitters)
        self.light_pdf_area = np.zeros(len(self.area))
        self.light_pdf_area[self.emitters] = self.emitter_prob / self.area[self.emitters]
        self.lights = scene.lights

    def intersect(self, o: np.ndarray, d: np.ndarray):
        """Closest hits of rays o, d (n, 3) float64: t (n,) (inf: miss), tri (n,) int (-1: miss),
        and the geometric normals (n, 3) by winding (zero for a miss)."""
        hits = self.tracer.closest_hit(o, d, parallel=self.parallel)
        normal = np.zeros((len(o), 3))
        h = hits.tri >= 0
        normal[h] = self.tracer.normals[hits.tri[h]]
        return hits.t, hits.tri, normal

    def occluded(self, o: np.ndarray, d: np.ndarray, tmax) -> np.ndarray:
        return self.tracer.occluded(o, d, tmax, parallel=self.parallel)

    def sample_emitters(self, rng: np.random.Generator, k: int):
        """k points on the emitters: y (k, 3), their triangles (k,) int, and p_A(y) (k,), the
        area density of the choice."""
        j = np.minimum(np.searchsorted(self.emitter_cdf, rng.random(k), side="right"),
                       len(self.emitters) - 1)
        tri = self.emitters[j]
        u1, u2 = rng.random(k), rng.random(k)
        r = np.sqrt(u1)
        c = self.corners[tri]
        y = ((1.0 - r)[:, None] * c[:, 0] + (r * (1.0 - u2))[:, None] * c[:, 1]
             + (r * u2)[:, None] * c[:, 2])
        return y, tri, self.emitter_prob[j] / self.area[tri]


@dataclass(frozen=True, eq=False)
class PathImage:
    """A path-traced image.

    image    : (H, W, 3) float64 linear RGB, the mean of `spp` samples per pixel
    variance : (H, W, 3) float64, the variance of that mean (sample variance / spp)
    rays     : total rays traced (camera, bounce and shadow rays);  seconds : wall time
    """

    image: np.ndarray
    variance: np.ndarray
    spp: int
    rays: int
    seconds: float


def _add(L: np.ndarray, index: np.ndarray, values: np.ndarray) -> None:
    for c in range(3):
        L[:, c] += np.bincount(index, weights=values[:, c], minlength=len(L))


def next_event(world: PathWorld, rng, p, n, wo, obj, beta, mis: bool = True
               ) -> tuple[np.ndarray, int]:
    """Direct light (k, 3) at vertices p (k, 3) with normals n (k, 3) facing wo (k, 3), objects
    obj (k,), throughputs beta (k, 3), from one emitter sample each and every delta light.
    mis: weigh the emitter sample by its MIS share (False at the last bounce, where no BSDF
    sample follows to take the rest).  Returns the contributions and the shadow rays traced."""
    k = len(p)
    out = np.zeros((k, 3))
    w_phong = 1.0 - world.refl[obj] - world.transp[obj]
    kd, ks, s = world.kd[obj], world.ks[obj], world.shininess[obj]
    start = p + world.offset * n
    rays = 0
    if len(world.emitters):
        y, tri, p_area = world.sample_emitters(rng, k)
        to_y = y - p
        dist2 = dot(to_y, to_y)
        wi = to_y / np.sqrt(np.maximum(dist2, 1e-300))[:, None]
        n_y = world.tracer.normals[tri]
        cos_x = dot(n, wi)
        cos_y = -dot(n_y, wi)
        side = np.where(cos_y >= 0.0, 1.0, -1.0)  # the emitter's face toward x
        cos_y = np.abs(cos_y)
        c = np.flatnonzero((cos_x > 0.0) & (cos_y > 0.0) & (w_phong > 0.0) & (dist2 > 0.0))
        end = y[c] + world.offset * side[c, None] * n_y[c]
        blocked = world.occluded(start[c], end - start[c], 1.0)
        rays += len(c)
        c = c[~blocked]
        f = phong_eval(kd[c], ks[c], s[c], n[c], wo[c], wi[c]) * w_phong[c, None]
        g = cos_x[c] * cos_y[c] / (dist2[c] * p_area[c])
        p_light = p_area[c] * dist2[c] / cos_y[c]
        p_bsdf = w_phong[c] * phong_pdf(world.p_diffuse[obj[c]], s[c], n[c], wo[c], wi[c])
        if mis:
            g *= p_light / (p_light + p_bsdf)
        out[c] += beta[c] * f * world.emission[world.tri_object[tri[c]]] * g[:, None]
    for light in world.lights:
        if isinstance(light, DirectionalLight):
            wi = np.broadcast_to(-light.direction, p.shape)
            direction, tmax = wi, None
        else:
            wi = light.position - p
            wi = wi / np.linalg.norm(wi, axis=1)[:, None]
            direction, tmax = light.position - start, 1.0
        cos_x = dot(n, wi)
        ok = (cos_x > 0.0) & (w_phong > 0.0)
        if isinstance(light, SpotLight):
            ok &= dot(-wi, light.direction) >= light.cos_cutoff
        c = np.flatnonzero(ok)
        blocked = world.occluded(start[c], direction[c], tmax)
        rays += len(c)
        c = c[~blocked]
        f = phong_eval(kd[c], ks[c], s[c], n[c], wo[c], wi[c]) * w_phong[c, None]
        out[c] += beta[c] * f * (math.pi * light.radiance) * cos_x[c, None]
    return out, rays


def trace_paths(world: PathWorld, o: np.ndarray, d: np.ndarray, rng: np.random.Generator,
                max_depth: int = DEFAULT_MAX_DEPTH, rr_start: int = RR_START_BOUNCE
                ) -> tuple[np.ndarray, int]:
    """Radiance (n, 3) float64 arriving along rays o, d (n, 3) float64 (unit d), one path each,
    and the number of rays traced.  rr_start: first bounce of Russian roulette (a number above
    max_depth turns it off)."""
    n_paths = len(o)
    L = np.zeros((n_paths, 3))
    background = world.scene.background
    path = np.arange(n_paths)
    beta = np.ones((n_paths, 3))
    count_emission = np.ones(n_paths, bool)  # camera or delta ray: emission counts fully
    bsdf_pdf = np.zeros(n_paths)  # solid-angle density of the last Phong-sampled direction
    rays = 0
    for bounce in range(1, max_depth + 1):
        t, tri, geo_n = world.intersect(o, d)
        rays += len(o)
        hit = tri >= 0
        seen = ~hit & count_emission
        L[path[seen]] += beta[seen] * background  # a path's index occurs once per bounce
        h = np.flatnonzero(hit)
        if len(h) == 0:
            break
        o, d, t, tri, geo_n = o[h], d[h], t[h], tri[h], geo_n[h]
        path, beta, count_emission, bsdf_pdf = path[h], beta[h], count_emission[h], bsdf_pdf[h]
        obj = world.tri_object[tri]
        p = o + t[:, None] * d
        entering = dot(geo_n, d) < 0.0
        n = np.where(entering[:, None], geo_n, -geo_n)  # faces the ray's origin
        wo = -d
        e = np.flatnonzero(count_emission)
        L[path[e]] += beta[e] * world.emission[obj[e]]
        e = np.flatnonzero(~count_emission & (world.light_pdf_area[tri] > 0.0))
        if len(e):  # an emitter found by BSDF sampling: its MIS share
            cos_y = np.abs(dot(geo_n[e], d[e]))
            p_light = world.light_pdf_area[tri[e]] * t[e] ** 2 / np.maximum(cos_y, 1e-300)
            w = bsdf_pdf[e] / (bsdf_pdf[e] + p_light)
            L[path[e]] += beta[e] * world.emission[obj[e]] * w[:, None]
        direct, shadow = next_event(world, rng, p, n, wo, obj, beta, mis=bounce < max_depth)
        rays += shadow
        L[path] += direct
        if bounce == max_depth:
            break
        k = len(p)
        refl, transp = world.refl[obj], world.transp[obj]
        u = rng.random(k)
        is_mirror = u < refl
        is_glass = ~is_mirror & (u < refl + transp)
        is_phong = ~is_mirror & ~is_glass
        new_d = np.empty((k, 3))
        new_o = p + world.offset * n
        factor = np.ones((k, 3))
        pdf_next = np.zeros(k)
        m = np.flatnonzero(is_mirror)
        new_d[m] = reflect(d[m], n[m])
        g = np.flatnonzero(is_glass)
        if len(g):
            eta = np.where(entering[g], 1.0 / world.ior[obj[g]], world.ior[obj[g]])
            new_d[g], tir = refract(d[g], n[g], eta)
            new_o[g] = p[g] + np.where(tir, 1.0, -1.0)[:, None] * world.offset * n[g]
        q = np.flatnonzero(is_phong)
        if len(q):
            oq = obj[q]
            wi = phong_sample(rng, world.p_diffuse[oq], world.shininess[oq], n[q], wo[q])
            f = phong_eval(world.kd[oq], world.ks[oq], world.shininess[oq], n[q], wo[q], wi)
            pdf = phong_pdf(world.p_diffuse[oq], world.shininess[oq], n[q], wo[q], wi)
            cos = dot(n[q], wi)
            ok = (cos > 0.0) & (pdf > 0.0)
            factor[q] = np.where(ok[:, None], f * (cos / np.where(ok, pdf, 1.0))[:, None], 0.0)
            new_d[q] = wi
            pdf_next[q] = (1.0 - refl[q] - transp[q]) * pdf
        beta = beta * factor
        alive = beta.max(axis=1) > 0.0
        if bounce >= rr_start:
            survive = np.minimum(beta.max(axis=1), RR_MAX_SURVIVAL)
            alive &= rng.random(k) < survive
            beta = beta / np.where(alive, survive, 1.0)[:, None]
        keep = np.flatnonzero(alive)
        if len(keep) == 0:
            break
        o, d, path, beta = new_o[keep], new_d[keep], path[keep], beta[keep]
        count_emission, bsdf_pdf = ~is_phong[keep], pdf_next[keep]
    return L, rays


def radiance_leaving(world: PathWorld, points: np.ndarray, normals: np.ndarray,
                     rng: np.random.Generator, max_depth: int = DEFAULT_MAX_DEPTH
                     ) -> tuple[np.ndarray, int]:
    """Radiance (k, 3) leaving surface points (k, 3) along their unit normals (k, 3) (the face
    to look at), one path each: a ray from just in front of each point, back along -normal.
    For Lambertian surfaces this is the radiance in every direction, what radiosity computes.
    The start is `LEAVING_STANDOFF` surface offsets out: clear of the float32 surface, far
    closer than any other geometry in front of it."""
    start = points + LEAVING_STANDOFF * world.offset * normals
    return trace_paths(world, start, -normals, rng, max_depth)


def camera_rays(camera, width: int, height: int, rows: np.ndarray, cols: np.ndarray,
                rng: np.random.Generator | None) -> tuple[np.ndarray, np.ndarray]:
    """Rays through pixels (rows[i], cols[i]) (k,) int: at a uniformly random point of the pixel
    (rng given) or its centre (rng None, as the masks sample), starting on the near plane
    (CONVENTIONS.md).  Returns origins, unit directions (k, 3) float64."""
    right, up, back = camera_basis(camera)
    jx = rng.random(len(rows)) if rng is not None else np.full(len(rows), 0.5)
    jy = rng.random(len(rows)) if rng is not None else np.full(len(rows), 0.5)
    half_h = math.tan(math.radians(camera.fov_y) / 2.0)
    half_w = half_h * width / height
    sx = ((cols + jx) / width * 2.0 - 1.0) * half_w
    sy = (1.0 - (rows + jy) / height * 2.0) * half_h
    d = sx[:, None] * right + sy[:, None] * up - back
    o = camera.eye + camera.near * d
    return o, d / np.linalg.norm(d, axis=1)[:, None]


def render(scene: Scene, spp: int = 16, seed: int = 0, max_depth: int = DEFAULT_MAX_DEPTH,
           rr_start: int = RR_START_BOUNCE, jitter: bool = True, backend: str = "embree",
           progress: bool | None = None) -> PathImage:
    """Path-trace `scene` with `spp` paths per pixel; see the module docstring.

    jitter : sample each pixel at random points (True) or always at its centre (False: then the
             image converges to the pixel-centre image that the masks and Whitted sample).
    The result depends on (scene, spp, seed, max_depth, rr_start, jitter) only.
    """
    for name, value, low in (("spp", spp, 1), ("max_depth", max_depth, 1)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
            raise ValueError(f"{name} must be a whole number >= {low}, got {value!r}")
    start = time.perf_counter()
    H, W = scene.height, scene.width
    per_row = W * spp
    rows_per_tile = max(1, TILE_PATHS // per_row)
    tiles = [slice(y, min(y + rows_per_tile, H)) for y in range(0, H, rows_per_tile)]
    seeds = np.random.SeedSequence(seed).spawn(len(tiles))
    threads = min(cpu_threads(), len(tiles))
    world = PathWorld(scene, backend, parallel=threads == 1)
    total = np.zeros((H * W, 3))
    squares = np.zeros((H * W, 3))
    counted = [0]

    def tile(job):
        rows, seq = job
        rng = np.random.default_rng(seq)
        y, x = np.divmod(np.arange(rows.start * W, rows.stop * W), W)
        pixel = np.repeat(y * W + x, spp)
        o, d = camera_rays(scene.camera, W, H, pixel // W, pixel % W, rng if jitter else None)
        L, rays = trace_paths(world, o, d, rng, max_depth, rr_start)
        return pixel, L, rays

    with Progress(len(tiles), f"path trace {scene.name}", enabled=progress) as bar:
        pool = ThreadPoolExecutor(threads) if threads > 1 else None
        done = (pool.map if pool else map)(tile, zip(tiles, seeds))
        try:
            for pixel, L, rays in done:
                _add(total, pixel, L)
                _add(squares, pixel, L * L)
                counted[0] += rays
                bar.update()
        finally:
            if pool:
                pool.shutdown(cancel_futures=True)
    mean = total / spp
    var = np.maximum(squares / spp - mean ** 2, 0.0) / max(spp - 1, 1)
    return PathImage(mean.reshape(H, W, 3), var.reshape(H, W, 3), spp, counted[0],
                     time.perf_counter() - start)
