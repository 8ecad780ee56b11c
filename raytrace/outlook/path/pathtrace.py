"""Unidirectional path tracing (Kajiya 1986) with next-event estimation, vectorised per bounce.

The estimator, for every path vertex x reached from the eye (all rays of one bounce traced at
once, per tile, like `raytrace.outlook.whitted`):

* emission seen directly: a camera ray, or a ray leaving a mirror / glass (delta) bounce, adds
  the radiance `Material.emission` of what it hits;
* next-event estimation at every non-delta vertex: one point y on the emissive triangles, chosen
  with probability proportional to area x mean emitted radiance and uniformly within the triangle,
  adds  f(wo, wi) L_e cos_x cos_y / (|x − y|^2 p_A(y))  if the segment is unblocked; each point /
  spot / directional light of `scene.lights` (an area light: each of its samples, also weighted by
  its cosine at the light, as in `raytrace.outlook.whitted`) adds  f · pi · radiance · cos_x (these
  delta lights keep the Whitted convention: irradiance pi · radiance · n·l, no distance fall-off, so
  a Lambertian surface gets kd · radiance · n·l as in Whitted);
* the next direction is drawn from the material (`raytrace.outlook.brdf`); emission found by a ray
  drawn from the Phong lobes is added too, and the two estimates of the same light are combined by
  multiple importance sampling (`raytrace.outlook.path.mis`, Veach 1995: the power heuristic by
  default, NEE's sample weighed p_light^2 / (p_light^2 + p_bsdf^2), the BSDF-sampled hit p_bsdf^2 /
  (p_light^2 + p_bsdf^2), both densities in solid angle, p_light = p_A(y)
  |x - y|^2 / cos_y; `mis` picks "balance", or "nee" for NEE alone).  MIS, not plain NEE: with
  NEE alone a point next to a large emitter (a corner of the furnace box) gets 1/r^2 spikes;
  the BSDF sample covers them.  Delta lights stay plain NEE (no BSDF sample can hit them);
* Russian roulette from bounce `RR_START_BOUNCE` on: a path survives with probability
  q = min(max_channel(throughput), RR_MAX_SURVIVAL) and its throughput is divided by q (from
  the fifth, not the third: ~20% less CPU time for the same error on the Cornell box at depth
  4 and 64, the third and fourth bounces' light being worth their rays).

`max_depth` is the number of bounces light may make between an emitter and the eye: 1 is direct
lighting (emission seen + NEE at the first hit), the default `DEFAULT_MAX_DEPTH` is deep enough
that the truncation is below the noise (Russian roulette ends paths long before).  A ray that
escapes shows `scene.background` to the camera and through delta bounces; the background does not
light the scene.  `scene.ambient` is ignored (the integrator computes what ambient fakes).

Every object is traced as its triangles (spheres as their icospheres), so the emitter that NEE
samples is exactly the surface that rays hit.  Random numbers: one `numpy` generator per tile,
spawned from `SeedSequence(seed)`, so an image depends on the seed only (not on the threads). With
`sampler` "sobol" (the default) the pixel jitter and the first `sobol.LD_BOUNCES` bounces' emitter
and BSDF samples are each pixel's Owen-scrambled Sobol points instead
(`raytrace.outlook.path.sobol`: stratified per pixel, each sample still uniform), which cuts the
error at equal samples 2-4x on the Cornell box; "independent" draws everything from the generator.

Two shadings, one estimator.  What happens between the Embree casts of a bounce runs either as the
numpy passes below (the reference, and the fallback) or compiled by numba
(`raytrace.outlook.path.pathkernels`, the `fast` extra), which draws the same random numbers here in
numpy and repeats the same float32 arithmetic: the same samples (`shading` picks one;
$SHADOWVOL_PATHTRACE forces it).

Layout and precision.  The path state is rows, (3, k) arrays (`brdf`'s `_rows` kernels), in
float32 (`pathstate.STATE`): Embree traces float32 anyway, and numpy's float32 loops are about
twice as fast.  What float32 costs here is bounded: a hit point lies within a few float32
spacings of `length_scale` (<= ~4e-7 of it) of its float64 value, and every ray leaves a surface
`surface_offset` = 1e-4 of `length_scale` out, so a ray cannot start behind the surface it left
(Whitted's own margin; these images are not masks, CONVENTIONS.md's exact segments are the
masks'); directions, cosines, densities and throughputs carry ~1e-7 relative errors, far below
any image's noise; random numbers are float32 (24 bits) except the emitter choice and the camera
jitter; what a path gathers is float32, its radiance sums it in float64 (so that the background
seen directly is exact), as do the per-pixel sums and squares.
"""

from __future__ import annotations

import math
import os
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from shadowvol.errors import InputError, MissingExtra
from shadowvol.scene import (
    AreaSample,
    DirectionalLight,
    Scene,
    SpotLight,
)

from raytrace.backends import cpu_threads
from raytrace.camera import camera_rays  # noqa: F401  (`pathtrace.camera_rays`, as before)
from raytrace.intersect import reflect, refract
from raytrace.outlook.brdf import (
    dot_rows,
    phong_eval_rows,
    phong_pdf_rows,
    phong_sample_rows,
)
from raytrace.outlook.progress import Progress

from .mis import DEFAULT_HEURISTIC, bsdf_weight, code, emitter_pdf, hit_pdf, weight
from .pathstate import RR_MAX_SURVIVAL, STATE, STATE_TINY, PathWorld, take
from .sobol import DEFAULT_SAMPLER, SAMPLERS, TileSamples, render_key

RR_START_BOUNCE = 5  # Russian roulette from the fifth bounce on (as Mitsuba 3's rr_depth)
DEFAULT_MAX_DEPTH = 64  # bounces; the truncation bias is below rho^64 of the image
TILE_PATHS = 1 << 15  # paths traced together: ~10 MB of arrays; sets the progress step
LEAVING_STANDOFF = 10.0  # `radiance_leaving` starts its rays this many surface offsets out
# the environment variable that picks the per-bounce shading (`shading`): auto, numpy, numba
SHADING_ENV = "SHADOWVOL_PATHTRACE"
SHADINGS = ("numpy", "numba")


@dataclass(frozen=True, eq=False)
class PathImage:
    """A path-traced image.

    image    : (H, W, 3) float64 linear RGB, the mean of `spp` samples per pixel
    variance : (H, W, 3) float64, the variance of that mean (sample variance / spp)
    rays     : total rays traced (camera, bounce and shadow rays);  seconds : wall time
    shading  : "numpy" or "numba" (`shading`), the per-bounce shading that ran
    """

    image: np.ndarray
    variance: np.ndarray
    spp: int
    rays: int
    seconds: float
    shading: str = "numpy"


def _scatter_add(L: np.ndarray, index: np.ndarray, values: np.ndarray) -> None:
    """L[:, index] += values for L (3, n), distinct indices (k,), values (3, k)."""
    for c in range(3):
        L[c, index] += values[c]


def next_event(world: PathWorld, rng, p, n, wo, surf: dict, beta, start, mis: bool = True,
               u=None, heuristic: str = DEFAULT_HEURISTIC) -> tuple[np.ndarray, int]:
    """Direct light (3, k) at vertices p (3, k) with normals n (3, k) facing wo (3, k), of
    surfaces surf (`PathWorld.surface`), throughputs beta (3, k), from one emitter sample each and
    every delta light; shadow rays leave from start (3, k), p + offset n.  mis: weigh the emitter
    sample by its MIS share (`raytrace.outlook.path.mis`, heuristic; False at the last bounce, where
    no BSDF sample follows to take the rest).  u: the emitter sample's uniforms
    (`PathWorld.sample_emitters`), else drawn from rng.  Returns the contributions and the shadow
    rays traced."""
    k = p.shape[1]
    out = np.zeros((3, k), STATE)
    w_phong, glossy = surf["phong"], surf["glossy"]
    kd, ks, s = surf["kd"], surf["ks"], surf["shininess"]
    rays = 0
    with np.errstate(divide="ignore", invalid="ignore"):
        if len(world.emitters):
            y, n_y, radiance, p_area = world.sample_emitters(rng, k, u)
            to_y = y - p
            dist2 = dot_rows(to_y, to_y)
            wi = to_y * (1.0 / np.sqrt(np.maximum(dist2, STATE_TINY)))
            cos_x = dot_rows(n, wi)
            cos_y = -dot_rows(n_y, wi)
            side = np.where(cos_y >= 0.0, STATE(world.offset), STATE(-world.offset))  # to x
            cos_y = np.abs(cos_y)
            c = np.flatnonzero((cos_x > 0.0) & (cos_y > 0.0) & (w_phong > 0.0) & (dist2 > 0.0))
            seg = y + side * n_y - start
            blocked = world.occluded_rows(take(start, c), take(seg, c), 1.0)
            rays += len(c)
            lit = np.zeros(k, bool)
            lit[c] = ~blocked
            # computed for all k, kept where lit (cheaper than gathering the lit ones)
            g = cos_x * cos_y / (dist2 * p_area)
            if mis and heuristic != "nee":
                p_light = emitter_pdf(p_area, dist2, cos_y)
                p_bsdf = w_phong * phong_pdf_rows(surf["p_diffuse"], s, n, wo, wi, glossy,
                                                  cos_t=cos_x)
                g *= weight(p_light, p_bsdf, heuristic)
            g = np.where(lit, g * w_phong, 0.0)  # lit implies cos_x > 0
            if world.any_glossy:
                out = beta * phong_eval_rows(kd, ks, s, n, wo, wi, glossy, cos_t=cos_x)
                out *= radiance
                out *= g
            else:  # Lambert: f = kd / pi
                out = beta * kd
                out *= radiance
                out *= g * STATE(1.0 / math.pi)
        for light in world.lights:
            if isinstance(light, DirectionalLight):
                wi = np.repeat(-np.asarray(light.direction, STATE)[:, None], k, axis=1)
                direction, tmax = wi, None
            else:
                to_l = np.asarray(light.position, STATE)[:, None] - p
                wi = to_l * (1.0 / np.sqrt(dot_rows(to_l, to_l)))
                direction, tmax = np.asarray(light.position, STATE)[:, None] - start, 1.0
            cos_x = dot_rows(n, wi)
            ok = (cos_x > 0.0) & (w_phong > 0.0)
            if isinstance(light, SpotLight):
                cos_light = -dot_rows(wi, np.asarray(light.direction, STATE)[:, None])
                ok &= cos_light >= light.cos_cutoff
            c = np.flatnonzero(ok)
            blocked = world.occluded_rows(take(start, c), take(direction, c), tmax)
            rays += len(c)
            lit = np.zeros(k, bool)
            lit[c] = ~blocked
            f = phong_eval_rows(kd, ks, s, n, wo, wi, glossy, cos_t=cos_x)
            g = np.where(lit, w_phong * cos_x, 0.0)
            if isinstance(light, AreaSample):   # weighted by its cosine at the light
                g *= np.maximum(cos_light, 0.0)
            out += beta * f * (math.pi * np.asarray(light.radiance, STATE)[:, None]) * g
    return out, rays


def trace_paths(world: PathWorld, o: np.ndarray, d: np.ndarray, rng: np.random.Generator,
                max_depth: int = DEFAULT_MAX_DEPTH, rr_start: int = RR_START_BOUNCE,
                shading_name: str | None = None, mis: str = DEFAULT_HEURISTIC
                ) -> tuple[np.ndarray, int]:
    """Radiance (n, 3) float64 arriving along rays o, d (n, 3) float64 (unit d), one path each,
    and the number of rays traced.  rr_start: first bounce of Russian roulette (a number above
    max_depth turns it off); shading_name, mis: as for `trace_rows`."""
    L, rays = trace_rows(world, np.asarray(o).T, np.asarray(d).T, rng, max_depth, rr_start,
                         shading_name, mis)
    return np.ascontiguousarray(L.T, np.float64), rays


def _delta_bounce(world, d, n, entering, surf, p, is_mirror, is_glass, new_o, new_d):
    """Directions (and, through glass, starts) of the mirror and glass bounces, in place in
    new_o, new_d (3, k).  Rare: done on (m, 3) copies with the Whitted formulas."""
    m = np.flatnonzero(is_mirror)
    if len(m):
        new_d[:, m] = reflect(take(d, m).T, take(n, m).T).T
    g = np.flatnonzero(is_glass)
    if len(g):
        ior = take(surf["ior"], g)
        eta = np.where(take(entering, g), 1.0 / ior, ior)
        ng = take(n, g)
        t, tir = refract(take(d, g).T, ng.T, eta)
        new_d[:, g] = t.T
        new_o[:, g] = take(p, g) + np.where(tir, 1.0, -1.0) * world.offset * ng


def _kernels():
    """`raytrace.outlook.path.pathkernels` (numba's compiled shading), or None where numba is
    missing."""
    try:
        from . import pathkernels
    except ImportError:  # numba absent, or too old or new for this numpy
        return None
    return pathkernels


def shading(choice: str | None = None) -> str:
    """Which per-bounce shading the path tracer runs: "numba" (`raytrace.outlook.path.pathkernels`,
    the `fast` extra) or "numpy" (the reference below).  choice None: $SHADOWVOL_PATHTRACE, and
    where that is unset or "auto", numba when it imports, else numpy.  Both give the same samples
    (`raytrace.outlook.path.pathkernels`).  An unknown name is an InputError naming where it came
    from; numba asked for but missing is a MissingExtra (exit status 2 in the CLI)."""
    where = "shading"
    if choice is None:
        choice, where = os.environ.get(SHADING_ENV, "auto").strip().lower() or "auto", \
            SHADING_ENV
    if choice not in SHADINGS + ("auto",):
        raise InputError(where, f"unknown path-tracer shading {choice!r} (one of: auto, "
                                f"{', '.join(SHADINGS)})")
    if choice == "numpy":
        return "numpy"
    if _kernels() is not None:
        return "numba"
    if choice == "numba":
        raise MissingExtra(f"{where}=numba (the path tracer's compiled shading)", "numba",
                           "fast")
    return "numpy"


def _untextured(used: str, scene: Scene) -> str:
    """The shading to run: numba's kernels read kd per triangle only, so a scene with
    textures or vertex colours is shaded in numpy (`PathWorld.textured_kd`)."""
    if used == "numba" and any(o.material.texture is not None or o.colors is not None
                               for o in scene.objects):
        return "numpy"
    return used


def trace_rows(world: PathWorld, o: np.ndarray, d: np.ndarray, rng: np.random.Generator,
               max_depth: int = DEFAULT_MAX_DEPTH, rr_start: int = RR_START_BOUNCE,
               shading_name: str | None = None, mis: str = DEFAULT_HEURISTIC,
               samples: TileSamples | None = None) -> tuple[np.ndarray, int]:
    """`trace_paths` with rays and radiance as rows: o, d (3, n) float -> L (3, n) float64.
    shading_name: "numpy", "numba" or None (`shading()` decides); mis: the heuristic
    (`raytrace.outlook.path.mis.HEURISTICS`); samples: the low-discrepancy numbers of these paths
    (`sobol.TileSamples`, path i its i-th), else every number is drawn from rng."""
    code(mis)
    if _untextured(shading(shading_name), world.scene) == "numba":
        return _kernels().trace_rows(world, o, d, rng, max_depth, rr_start, mis, samples)
    return _trace_rows_numpy(world, o, d, rng, max_depth, rr_start, mis, samples)


def _trace_rows_numpy(world: PathWorld, o: np.ndarray, d: np.ndarray,
                      rng: np.random.Generator, max_depth: int, rr_start: int,
                      heuristic: str, samples) -> tuple[np.ndarray, int]:
    """The numpy reference of `trace_rows`: every stage a few whole-array passes."""
    o = np.ascontiguousarray(o, STATE)
    d = np.ascontiguousarray(d, STATE)
    n_paths = o.shape[1]
    L = np.zeros((3, n_paths))  # float64: a background pixel shows the background exactly
    background = np.asarray(world.scene.background, np.float64)[:, None]
    shows_background = bool(background.any())
    path = np.arange(n_paths)
    beta = np.ones((3, n_paths), STATE)
    count_emission = np.ones(n_paths, bool)  # camera or delta ray: emission counts fully
    bsdf_pdf = np.zeros(n_paths, STATE)  # solid-angle density of the last Phong-sampled direction
    rays = 0
    for bounce in range(1, max_depth + 1):
        tri = world.closest_rows(o, d)
        rays += len(tri)
        hit = tri >= 0
        h = np.flatnonzero(hit)
        if len(h) < len(tri):  # compact to the hits (a camera ray through the open front)
            if shows_background:
                seen = np.flatnonzero(~hit & count_emission)
                _scatter_add(L, take(path, seen), take(beta, seen) * background)
            if len(h) == 0:
                break
            o, d, tri, path, beta, count_emission, bsdf_pdf = (
                take(x, h) for x in (o, d, tri, path, beta, count_emission, bsdf_pdf))
        surf = world.surface(tri)
        geo_n = surf["normal"]
        d_n = dot_rows(geo_n, d)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (surf["plane_d"] - dot_rows(geo_n, o)) / d_n  # as backends.refine
        t = np.where(np.isfinite(t), t, 0.0)
        p = o + t * d
        surf["kd"] = world.textured_kd(surf["kd"], tri, p)
        entering = d_n < 0.0
        n = geo_n * np.where(entering, STATE(1.0), STATE(-1.0))  # faces the ray's origin
        wo = -d if world.any_glossy else None  # only the glossy lobe looks at wo
        if world.any_emits:
            _emission_seen(world, L, surf, tri, path, beta, count_emission, bsdf_pdf, d_n, t,
                           heuristic)
        new_o = p + world.offset * n  # where shadow rays and the next ray start
        u_light, u_bsdf = (None, None) if samples is None else \
            samples.bounce(bounce, path, bounce < max_depth, world.any_delta, bounce >= rr_start)
        direct, shadow = next_event(world, rng, p, n, wo, surf, beta, new_o,
                                    bounce < max_depth, u_light, heuristic)
        rays += shadow
        _scatter_add(L, path, direct)
        if bounce == max_depth:
            break
        k = len(tri)
        new_d, factor, pdf_next, is_phong = _scatter(world, rng, surf, d, n, wo, entering, p,
                                                     new_o, u_bsdf)
        beta = beta * factor
        strongest = np.maximum(np.maximum(beta[0], beta[1]), beta[2])
        alive = strongest > 0.0
        if bounce >= rr_start:
            survive = np.minimum(strongest, RR_MAX_SURVIVAL)
            u_rr = rng.random(k, dtype=STATE) if u_bsdf is None else u_bsdf[3]
            alive &= u_rr < survive
            beta = beta * (1.0 / np.where(alive, survive, 1.0))
        keep = np.flatnonzero(alive)
        if len(keep) == 0:
            break
        if len(keep) == k:
            o, d, count_emission, bsdf_pdf = new_o, new_d, ~is_phong, pdf_next
        else:
            o, d, path, beta, count_emission, bsdf_pdf = (
                take(x, keep) for x in (new_o, new_d, path, beta, ~is_phong, pdf_next))
    return L, rays


def _emission_seen(world: PathWorld, L, surf: dict, tri, path, beta, count_emission,
                   bsdf_pdf, d_n, t, heuristic: str) -> None:
    """Add into L (3, n_paths) the emission the hits tri (k,) see: whole where the ray was a
    camera or delta ray (count_emission), else, found by BSDF sampling, its MIS share (none
    for heuristic "nee")."""
    emits = surf["emits"]
    e = np.flatnonzero(count_emission & emits)
    if len(e):
        _scatter_add(L, take(path, e),
                     take(beta, e) * take(world.tri_emission, take(tri, e)))
    e = np.flatnonzero(~count_emission & emits) if heuristic != "nee" else []
    if len(e):  # an emitter found by BSDF sampling: its MIS share
        te = take(tri, e)
        p_light = hit_pdf(take(surf["light_pdf"], e), take(t, e), np.abs(take(d_n, e)))
        w = bsdf_weight(take(bsdf_pdf, e), p_light, heuristic)
        _scatter_add(L, take(path, e),
                     take(beta, e) * take(world.tri_emission, te) * w)


def _scatter(world: PathWorld, rng, surf: dict, d, n, wo, entering, p, new_o, u=None):
    """The next direction of k paths at hits p (3, k): the lobe chosen (a mirror or glass
    bounce with its weights, else the Phong lobes), new_d (3, k), the throughput factor
    (3, k), the density pdf_next (k,) of a Phong sample (0 after a delta bounce) and
    is_phong (k,) bool; glass moves its rays' starts in new_o (3, k) in place.  u: the
    uniforms (the lobe choice, the cosine lobe's two, (k,) `STATE` each; `sobol.TileSamples`),
    else drawn from rng."""
    k = p.shape[1]
    if world.any_delta:
        u_lobe = rng.random(k, dtype=STATE) if u is None else u[0]
        is_mirror = u_lobe < surf["refl"]
        is_glass = ~is_mirror & (u_lobe < surf["refl"] + surf["transp"])
        is_phong = ~is_mirror & ~is_glass
    else:
        is_phong = np.ones(k, bool)
    # the Phong lobes for all (cheaper than gathering); the delta bounces overwrite theirs
    s, p_d, glossy = surf["shininess"], surf["p_diffuse"], surf["glossy"]
    new_d = phong_sample_rows(rng, p_d, s, n, wo, glossy, None if u is None else u[1:3])
    cos = dot_rows(n, new_d)
    pdf = phong_pdf_rows(p_d, s, n, wo, new_d, glossy, cos_t=cos)
    if world.any_glossy:
        f = phong_eval_rows(surf["kd"], surf["ks"], s, n, wo, new_d, glossy, cos_t=cos)
        ok = (cos > 0.0) & (pdf > 0.0)
        factor = f * np.where(ok, cos / np.where(ok, pdf, 1.0), 0.0)
    else:  # Lambert: f cos / pdf = (kd / pi) cos / (cos / pi) = kd where pdf > 0
        factor = surf["kd"] * (pdf > 0.0)
    pdf_next = surf["phong"] * pdf
    if world.any_delta:
        factor[:, ~is_phong] = 1.0
        pdf_next[~is_phong] = 0.0
        _delta_bounce(world, d, n, entering, surf, p, is_mirror, is_glass, new_o, new_d)
    return new_d, factor, pdf_next, is_phong


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


def render(scene: Scene, spp: int = 16, seed: int = 0, max_depth: int = DEFAULT_MAX_DEPTH,
           rr_start: int = RR_START_BOUNCE, jitter: bool = True, backend: str = "embree",
           progress: bool | None = None, shading_name: str | None = None,
           mis: str = DEFAULT_HEURISTIC, sampler: str = DEFAULT_SAMPLER) -> PathImage:
    """Path-trace `scene` with `spp` paths per pixel; see the module docstring.

    jitter : sample each pixel at random points (True) or always at its centre (False: then the
             image converges to the pixel-centre image that the masks and Whitted sample).
    shading_name : "numpy", "numba" or None ($SHADOWVOL_PATHTRACE, else numba if installed). mis :
    "power", "balance" or "nee" (`raytrace.outlook.path.mis`);  sampler : "sobol"
    (`raytrace.outlook.path.sobol`:
          each pixel's samples stratified) or "independent" (every number from the tile's
          generator).
    The result depends on (scene, spp, seed, max_depth, rr_start, jitter, mis, sampler) only:
    tiles of whole rows, one random stream each, summed in tile order whatever the threads
    (and the same samples from either shading: `raytrace.outlook.path.pathkernels`).
    """
    for name, value, low in (("spp", spp, 1), ("max_depth", max_depth, 1)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
            raise ValueError(f"{name} must be a whole number >= {low}, got {value!r}")
    code(mis)
    if sampler not in SAMPLERS:
        raise ValueError(f"sampler must be one of {', '.join(SAMPLERS)}, got {sampler!r}")
    key = render_key(seed)
    used = _untextured(shading(shading_name), scene)
    start = time.perf_counter()
    H, W = scene.height, scene.width
    per_row = W * spp
    rows_per_tile = max(1, TILE_PATHS // per_row)
    tiles = [slice(y, min(y + rows_per_tile, H)) for y in range(0, H, rows_per_tile)]
    seeds = np.random.SeedSequence(seed).spawn(len(tiles))
    threads = min(cpu_threads(), len(tiles))
    world = PathWorld(scene, backend, parallel=threads == 1)
    total = np.zeros((3, H * W))  # sums of the samples per pixel, and of their squares
    squares = np.zeros((3, H * W))
    counted = [0]

    def tile(job):
        rows, seq = job
        rng = np.random.default_rng(seq)
        first, last = rows.start * W, rows.stop * W
        samples = TileSamples(key, first, last - first, spp, used == "numba") \
            if sampler == "sobol" else None
        pixel_jitter = samples.camera() if samples is not None and jitter else None
        # the tile's pixels row by row, spp times over: a pixel's samples are summed over
        # a middle axis (numpy's reductions over a short last axis are slow)
        if used == "numba":  # the same rays, compiled
            o, d = _kernels().camera_rays(scene.camera, W, H, rows, spp,
                                          rng if jitter else None, pixel_jitter)
        else:
            row = np.tile(np.repeat(np.arange(rows.start, rows.stop), W), spp)
            col = np.tile(np.arange(W), (rows.stop - rows.start) * spp)
            o, d = camera_rays(scene.camera, W, H, row, col, rng if jitter else None,
                               pixel_jitter)
        L, rays = trace_rows(world, o, d, rng, max_depth, rr_start, used, mis, samples)
        L = L.reshape(3, spp, last - first)
        return slice(first, last), L.sum(axis=1), (L * L).sum(axis=1), rays

    with Progress(len(tiles), f"path trace {scene.name}", enabled=progress) as bar:
        pool = ThreadPoolExecutor(threads) if threads > 1 else None
        done = (pool.map if pool else map)(tile, zip(tiles, seeds))
        try:
            for pixels, sum_l, sum_l2, rays in done:
                total[:, pixels] = sum_l
                squares[:, pixels] = sum_l2
                counted[0] += rays
                bar.update()
        finally:
            if pool:
                pool.shutdown(cancel_futures=True)
    mean = total.T / spp
    var = np.maximum(squares.T / spp - mean ** 2, 0.0) / max(spp - 1, 1)
    return PathImage(mean.reshape(H, W, 3), var.reshape(H, W, 3), spp, counted[0],
                     time.perf_counter() - start, used)
