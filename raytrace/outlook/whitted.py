"""Whitted ray tracing, vectorised per generation.

All rays of one depth are traced at once (per tile of the image, see `TILE_RAYS`): primary rays
are generation 0; a hit on a reflective or transparent surface spawns the next generation's
reflection and refraction rays.  The colour of a ray that hits a surface is

    local · (1 − refl − transp) + refl · reflected + transp · refracted

and, at the depth limit (and for max_depth == 0), the local term alone, unweighted — so
`render(scene, max_depth=0)` is exactly the direct lighting the rasterizer draws.  A ray that
hits nothing gets `scene.background`.  The recursion is unrolled into per-ray weights: each ray
carries the product of the refl / transp factors along its path and adds weight · its own term to
its pixel.

The local term is Phong:

    ka · scene.ambient + Σ_visible lights [kd · max(n·l, 0) + ks · max(r·v, 0)^shininess] · radiance

where a light is visible when n·l > 0, a spot light's cone contains the point, and no object lies
between the point and the light (hard shadows; transparent objects are opaque to shadow rays, as
in the rasterizer).  No distance attenuation.  An area light is the sum of its samples
(`shadowvol.scene.hard_lights`), each with its share of the radiance and, for a rect or disk,
its cosine at the light: soft shadows, also in mirrors and through glass.

Geometry: objects with an analytic form (Sphere, Parallelogram) are intersected exactly; the
others (meshes, boxes) go through the triangle backend; the nearest hit wins.  Shading normals
are exact for analytic shapes and the face normal for triangles, flipped to face the incoming
ray.  Refraction decides entering / leaving by the geometric normal (outward for spheres, by
winding for triangles, edge_u × edge_v for parallelograms) against the ray, and assumes the
other side is air (ior 1): nested media are not tracked.

Distributed ray tracing (Cook, Porter, Carpenter 1984) generalises three of these: `spp` stratified
samples per pixel through a box or tent filter (antialiasing), a lens of radius `camera.aperture`
focused at `camera.focus` (depth of field) and a material's `roughness` (a glossy lobe instead of
the mirror ray, one ray per pixel sample and generation), each dimension stratified over the pixel's
samples (`raytrace.outlook.sampling`).  An area light stays its N fixed samples
(`AreaLight.positions`, the masks' light), all of them summed at every hit: the soft shadow of each
pixel sample is today's, so the image converges to today's averaged over the pixel.  At spp 1 with
no lens and no roughness, the image is the classic one, bit for bit: the same pixel-centre rays
(`primary_rays`) and the same mirror rays.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from shadowvol.scene import (
    DirectionalLight,
    Parallelogram,
    Scene,
    Sphere,
    SpotLight,
    emission_cosine,
    hard_lights,
)

from raytrace.backends import cpu_threads, make_backend
from raytrace.camera import primary_rays, sample_rays
from raytrace.intersect import dot, ray_parallelogram, ray_sphere, reflect, refract
from raytrace.texture import SurfaceColours
from raytrace.tolerances import surface_offset

from .progress import Progress
from .sampling import FILTERS, concentric_disk, glossy, pixel_offsets, stratified

# Primary rays per tile: bounds memory (a generation holds a few dozen float64 values per ray)
# and sets the progress bar's step.  Tiles are traced one per core at a time.
TILE_RAYS = 1 << 15


class World:
    """What the tracer intersects: the analytic objects, one triangle backend for the rest,
    and every object's material as arrays indexed by object.

    kind     : (K,) int: 0 sphere, 1 parallelogram, 2 triangles
    center   : (K, 3), radius : (K,)         spheres
    normal   : (K, 3)                         parallelograms (unit, edge_u × edge_v)
    ka, kd, ks : (K, 3);  shininess, refl, transp, ior, roughness : (K,)
    """

    SPHERE, PARALLELOGRAM, TRIANGLES = 0, 1, 2

    def __init__(self, scene: Scene, backend: str = "embree", parallel: bool = True):
        # parallel: may the triangle backend split its rays over the cores?  Not when the
        # caller already runs one tile per core.
        self.parallel = parallel
        objs = scene.objects
        self.offset = surface_offset(scene)
        K = len(objs)
        self.kind = np.full(K, self.TRIANGLES)
        self.center = np.zeros((K, 3))
        self.radius = np.ones(K)
        self.normal = np.zeros((K, 3))
        self.analytic = []
        for i, o in enumerate(objs):
            if isinstance(o.analytic, Sphere):
                self.kind[i] = self.SPHERE
                self.center[i], self.radius[i] = o.analytic.center, o.analytic.radius
                self.analytic.append((i, o.analytic))
            elif isinstance(o.analytic, Parallelogram):
                self.kind[i] = self.PARALLELOGRAM
                self.normal[i] = o.analytic.normal
                self.analytic.append((i, o.analytic))
        meshes = [i for i in range(K) if self.kind[i] == self.TRIANGLES]
        self.tracer = None
        if meshes:
            offsets = np.cumsum([0] + [len(objs[i].vertices) for i in meshes])
            vertices = np.concatenate([objs[i].vertices for i in meshes])
            faces = np.concatenate([objs[i].faces + off for i, off in zip(meshes, offsets)])
            self.tri_object = np.concatenate([np.full(len(objs[i].faces), i) for i in meshes])
            self.tracer = make_backend(backend, vertices, faces)
            # each object's first triangle in the backend (its faces' own indices: `hits`)
            self.tri_first = np.zeros(K, np.int64)
            self.tri_first[meshes] = np.cumsum([0] + [len(objs[i].faces) for i in meshes])[:-1]
        # textures and vertex colours (None: the scene has neither)
        self.surface = SurfaceColours.of(scene)
        # the shadow switches: shadow rays meet the casting objects only, and are not cast
        # from an object that receives none (`Object.cast_shadows`, `receive_shadows`)
        self.receives = np.array([o.receive_shadows for o in objs], bool)
        self.occluders, self.shadow_tracer = self.analytic, self.tracer
        if not all(o.cast_shadows for o in objs):
            self.occluders = [(i, a) for i, a in self.analytic if objs[i].cast_shadows]
            casting = [i for i in meshes if objs[i].cast_shadows]
            self.shadow_tracer = None if not casting else make_backend(
                backend, vertices, faces[np.isin(self.tri_object, casting)])
        m = [o.material for o in objs]
        self.ka = np.array([x.ambient for x in m])
        self.kd = np.array([x.diffuse for x in m])
        self.ks = np.array([x.specular for x in m])
        self.shininess = np.array([x.shininess for x in m])
        self.refl = np.array([x.reflectivity for x in m])
        self.transp = np.array([x.transparency for x in m])
        self.ior = np.array([x.ior for x in m])
        self.roughness = np.array([x.roughness for x in m])

    def nearest(self, o: np.ndarray, d: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Nearest hits of rays o, d (n, 3) float64.

        Returns t (n,) float64 (inf: miss), obj (n,) int (-1: miss) and the geometric normal
        (n, 3) float64, unit, outward / by winding (not yet facing the ray).
        """
        return self.hits(o, d)[:3]

    def base_colour(self, obj: np.ndarray, tri: np.ndarray, p: np.ndarray
                    ) -> np.ndarray | None:
        """(k,) hits' base colour (k, 3) float64 (`raytrace.texture`), from `hits`' obj and
        tri and the points p (k, 3); None where the scene has no texture nor vertex colour
        (1 everywhere)."""
        if self.surface is None:
            return None
        out = np.ones((len(obj), 3))
        m = np.flatnonzero(tri >= 0)   # triangles only: analytic shapes are untextured
        out[m] = self.surface.colour(obj[m], tri[m] - self.tri_first[obj[m]], p[m])
        return out

    def hits(self, o: np.ndarray, d: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """`nearest`, and the hit triangle's index in the backend (n,) int (-1: a miss or an
        analytic shape)."""
        n = len(o)
        t = np.full(n, np.inf)
        obj = np.full(n, -1)
        for i, shape in self.analytic:
            if isinstance(shape, Sphere):
                lam = ray_sphere(o, d, shape.center, shape.radius)
            else:
                lam = ray_parallelogram(o, d, shape.origin, shape.edge_u, shape.edge_v)
            closer = lam < t
            t[closer], obj[closer] = lam[closer], i
        tri = np.full(n, -1)
        if self.tracer is not None:
            hits = self.tracer.closest_hit(o, d, tmax=t, parallel=self.parallel)
            closer = (hits.tri >= 0) & (hits.t < t)
            t[closer], obj[closer], tri[closer] = hits.t[closer], \
                self.tri_object[hits.tri[closer]], hits.tri[closer]
        hit = obj >= 0
        p = o + np.where(hit, t, 0.0)[:, None] * d
        kind = np.where(hit, self.kind[obj], -1)
        normal = np.zeros((n, 3))
        s = kind == self.SPHERE
        normal[s] = (p[s] - self.center[obj[s]]) / self.radius[obj[s], None]
        q = kind == self.PARALLELOGRAM
        normal[q] = self.normal[obj[q]]
        m = kind == self.TRIANGLES
        if m.any():
            normal[m] = self.tracer.normals[tri[m]]
        return t, obj, normal, tri

    def occluded(self, o: np.ndarray, d: np.ndarray, tmax: float | None) -> np.ndarray:
        """(n,) bool: does any object lie on the rays o + λd, 0 < λ < tmax (None: anywhere)?"""
        bound = np.inf if tmax is None else tmax
        blocked = np.zeros(len(o), bool)
        for _, shape in self.occluders:
            if isinstance(shape, Sphere):
                lam = ray_sphere(o, d, shape.center, shape.radius)
            else:
                lam = ray_parallelogram(o, d, shape.origin, shape.edge_u, shape.edge_v)
            blocked |= lam < bound
        if self.shadow_tracer is not None:
            rest = np.flatnonzero(~blocked)
            blocked[rest] = self.shadow_tracer.occluded(o[rest], d[rest], tmax,
                                                        parallel=self.parallel)
        return blocked


@dataclass(frozen=True, eq=False)
class ShadowRays:
    """The shadow rays from k surface points toward one light, exactly as `local_colour`
    traces them (the ray-tree exercise, raytrace.outlook.raytree, reads them too).

    to_light  : (k, 3) float64, unit direction l from each point toward the light
    n_dot_l   : (k,) float64
    facing    : (k,) bool, n·l > 0
    in_cone   : (k,) bool, inside a spot light's cone (True for other lights)
    origin    : (k, 3) float64, where each shadow ray starts: p + offset·n (the viewer's side)
    direction : (k, 3) float64, the direction traced: −light.direction for a directional
                light (tmax None: anywhere along the ray), else light.position − origin, not
                normalised, with tmax 1 (the segment from the start to the light)
    tmax      : float or None
    blocked   : (k,) bool, an object lies on the shadow ray; traced only where facing &
                in_cone (a point facing away or outside the cone casts no shadow ray: False)
    """

    to_light: np.ndarray
    n_dot_l: np.ndarray
    facing: np.ndarray
    in_cone: np.ndarray
    origin: np.ndarray
    direction: np.ndarray
    tmax: float | None
    blocked: np.ndarray

    @property
    def visible(self) -> np.ndarray:
        """(k,) bool: the light reaches the point (facing, in the cone, not blocked)."""
        return self.facing & self.in_cone & ~self.blocked


def shadow_rays(world: World, light, p: np.ndarray, n: np.ndarray,
                obj: np.ndarray | None = None) -> ShadowRays:
    """Shadow rays from points p (k, 3) with unit normals n (k, 3) facing the viewer toward
    `light`; see `ShadowRays`.  obj (k,): the points' objects, none of whose points casts a
    ray when it receives no shadow (nor any point when the light casts none)."""
    start = p + world.offset * n  # shadow rays leave on the viewer's side (n·l > 0 there)
    if isinstance(light, DirectionalLight):
        to_light = np.broadcast_to(-light.direction, p.shape)
        tmax = None
        direction = to_light
    else:
        to_light = light.position - p
        tmax = 1.0  # the segment start -> light, with an unnormalised direction
        direction = light.position - start
    dist = np.linalg.norm(to_light, axis=1)
    l = to_light / dist[:, None]
    n_dot_l = dot(n, l)
    facing = n_dot_l > 0.0
    in_cone = np.ones(len(p), bool)
    if isinstance(light, SpotLight):
        in_cone = dot(-l, light.direction) >= light.cos_cutoff
    cast = facing & in_cone & light.shadows
    c = np.flatnonzero(cast if obj is None else cast & world.receives[obj])
    blocked = np.zeros(len(p), bool)
    blocked[c] = world.occluded(start[c], direction[c], tmax)
    return ShadowRays(l, n_dot_l, facing, in_cone, start, direction, tmax, blocked)


def local_colour(world: World, scene: Scene, p, n, view, obj, base=None) -> np.ndarray:
    """Phong local term (k, 3) float64 at points p (k, 3) with unit normals n (k, 3) facing the
    viewer, unit view directions `view` (k, 3) (toward the viewer), objects obj (k,); `base`
    (k, 3): the base colour multiplying ka and kd (`World.base_colour`; None: 1)."""
    ka, kd = world.ka[obj], world.kd[obj]
    if base is not None:
        ka, kd = ka * base, kd * base
    colour = ka * scene.ambient
    # an area light is its samples, each weighted by its share and its cosine at the light
    for light in (hard for lt in scene.lights for hard in hard_lights(lt)):
        rays = shadow_rays(world, light, p, n, obj)
        c = np.flatnonzero(rays.visible)
        l, n_dot_l = rays.to_light, rays.n_dot_l
        r = reflect(-l[c], n[c])  # the light's direction mirrored about n
        r_dot_v = np.maximum(dot(r, view[c]), 0.0)
        o = obj[c]
        term = (kd[c] * n_dot_l[c, None]
                + world.ks[o] * (r_dot_v ** world.shininess[o])[:, None])
        colour[c] += term * light.radiance * np.reshape(emission_cosine(light, l[c]), (-1, 1))
    return colour


def surface_frame(o, d, t, geo_n) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where rays o, d (k, 3) hit at t (k,) with geometric normals geo_n (k, 3): the points p
    (k, 3) float64, `entering` (k,) bool (the ray meets the geometric normal's front: d·n < 0)
    and the shading normals (k, 3), unit, facing the ray."""
    p = o + t[:, None] * d
    entering = dot(geo_n, d) < 0.0
    n = np.where(entering[:, None], geo_n, -geo_n)  # shading normal, facing the ray
    return p, entering, n


@dataclass(frozen=True, eq=False)
class Secondary:
    """The rays spawned at k hits on the way to the next generation.

    reflect_index : (kr,) int, which hits have refl > 0: they spawn a mirror ray
    reflect_origin, reflect_direction : (kr, 3) float64 (unit directions)
    refract_index : (ks,) int, which hits have transp > 0: they spawn a refracted ray
    refract_origin, refract_direction : (ks, 3) float64 (unit directions)
    tir           : (ks,) bool, total internal reflection: the "refracted" ray is the mirror
                    direction and starts on the ray's side
    """

    reflect_index: np.ndarray
    reflect_origin: np.ndarray
    reflect_direction: np.ndarray
    refract_index: np.ndarray
    refract_origin: np.ndarray
    refract_direction: np.ndarray
    tir: np.ndarray


def secondary_rays(world: World, p, n, d, entering, obj, u=None) -> Secondary:
    """Reflected and refracted rays at hits p (k, 3) with shading normals n (k, 3) (facing the
    ray), incoming unit directions d (k, 3), `entering` (k,) bool, objects obj (k,).

    u : (k, 2) float64 in [0, 1)², the glossy samples; None: every reflection is the mirror
        (roughness ignored).  A roughness of 0 is the mirror either way.
    """
    r = np.flatnonzero(world.refl[obj] > 0.0)
    mirror = reflect(d[r], n[r])
    rough = world.roughness[obj[r]]
    g = np.flatnonzero(rough > 0.0) if u is not None else ()
    if len(g):
        mirror[g] = glossy(mirror[g], n[r[g]], rough[g], u[r[g]])
    s = np.flatnonzero(world.transp[obj] > 0.0)
    # Reflection leaves on the ray's side; refraction crosses to the other side (unless
    # it is totally reflected inside, when `refract` hands back the mirror direction).
    eta = np.where(entering[s], 1.0 / world.ior[obj[s]], world.ior[obj[s]])
    refr_dir, tir = refract(d[s], n[s], eta)
    side = np.where(tir, 1.0, -1.0)[:, None]
    return Secondary(r, p[r] + world.offset * n[r], mirror,
                     s, p[s] + side * world.offset * n[s], refr_dir, tir)


def trace(world: World, scene: Scene, origins, directions, max_depth: int,
          glossy_samples=None) -> np.ndarray:
    """Colours (n, 3) float64 of rays origins, directions (n, 3) (unit directions).

    glossy_samples : None (mirrors), or a function of the generation (0, 1, ...) giving the
                     glossy samples (n, 2) in [0, 1)² of that generation per primary ray.
    """
    n_rays = len(origins)
    colour = np.zeros((n_rays, 3))
    o, d = origins, directions
    pixel = np.arange(n_rays)  # which primary ray each ray of this generation belongs to
    weight = np.ones(n_rays)  # product of refl / transp factors along the path
    for depth in range(max_depth + 1):
        t, obj, geo_n, tri = world.hits(o, d)
        hit = obj >= 0
        miss = ~hit
        _accumulate(colour, pixel[miss], weight[miss, None] * scene.background)
        if not hit.any():
            break
        h = np.flatnonzero(hit)
        o, d, t, obj, geo_n, pixel, weight, tri = o[h], d[h], t[h], obj[h], geo_n[h], \
            pixel[h], weight[h], tri[h]
        p, entering, n = surface_frame(o, d, t, geo_n)
        local = local_colour(world, scene, p, n, -d, obj, world.base_colour(obj, tri, p))
        refl, transp = world.refl[obj], world.transp[obj]
        if depth == max_depth:
            _accumulate(colour, pixel, weight[:, None] * local)
            break
        _accumulate(colour, pixel, (weight * (1.0 - refl - transp))[:, None] * local)
        u = None if glossy_samples is None else glossy_samples(depth)[pixel]
        sec = secondary_rays(world, p, n, d, entering, obj, u)
        r, s = sec.reflect_index, sec.refract_index
        o = np.concatenate([sec.reflect_origin, sec.refract_origin])
        d = np.concatenate([sec.reflect_direction, sec.refract_direction])
        pixel = np.concatenate([pixel[r], pixel[s]])
        weight = np.concatenate([weight[r] * refl[r], weight[s] * transp[s]])
        if len(o) == 0:
            break
    return colour


def _accumulate(colour: np.ndarray, index: np.ndarray, values: np.ndarray) -> None:
    """colour[index] += values, with repeated indices summed (several rays per pixel)."""
    for c in range(3):
        colour[:, c] += np.bincount(index, weights=values[:, c], minlength=len(colour))


def render(scene: Scene, max_depth: int | None = None, backend: str = "embree",
           progress: bool | None = None, spp: int = 1, seed: int = 0,
           pixel_filter: str = "box") -> np.ndarray:
    """Ray-trace `scene`: (H, W, 3) float64 linear RGB, row 0 at the top.

    max_depth    : reflection / refraction generations (default `scene.max_depth`); 0 gives the
                   direct lighting alone (exactly what the rasterizer draws).
    backend      : "embree" or "numpy", for objects without an analytic form (meshes, boxes).
    progress     : a progress bar on stderr: None (default) when stderr is a terminal.
    spp          : samples per pixel (`raytrace.outlook.sampling`); 1 is the pixel centre.
    seed         : >= 0; the same seed gives the same image, whatever the number of threads.
    pixel_filter : "box" or "tent" (`raytrace.outlook.sampling.pixel_offsets`).
    """
    depth = scene.max_depth if max_depth is None else max_depth
    if isinstance(depth, bool) or not isinstance(depth, (int, np.integer)) or depth < 0:
        raise ValueError(f"max_depth must be a whole number >= 0, got {depth!r}")
    for name, value in (("spp", spp), ("seed", seed)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) \
                or value < (name == "spp"):
            raise ValueError(f"{name} must be a whole number >= {int(name == 'spp')}, "
                             f"got {value!r}")
    if pixel_filter not in FILTERS:
        raise ValueError(f"filter must be one of {', '.join(FILTERS)}, got {pixel_filter!r}")
    H, W = scene.height, scene.width
    rows_per_tile = max(1, TILE_RAYS // (W * spp))
    tiles = [slice(y, min(y + rows_per_tile, H)) for y in range(0, H, rows_per_tile)]
    # One tile per core at a time: Embree and numpy's larger operations release the GIL.
    threads = min(cpu_threads(), len(tiles))
    world = World(scene, backend, parallel=threads == 1)
    rough = bool((world.roughness * world.refl).any())
    distributed = spp > 1 or scene.camera.aperture > 0.0 or rough
    image = np.zeros((H, W, 3))

    def trace_tile(rows: slice) -> tuple[slice, np.ndarray]:
        if not distributed:
            o, d = primary_rays(scene.camera, W, H, rows)
            return rows, trace(world, scene, o, d, depth).reshape(-1, W, 3)
        return rows, _distributed_tile(world, scene, rows, depth, spp, seed, pixel_filter,
                                       rough)

    with Progress(len(tiles), f"raytrace {scene.name}", enabled=progress) as bar:
        if threads == 1:
            done = map(trace_tile, tiles)
        else:
            pool = ThreadPoolExecutor(threads)
            done = pool.map(trace_tile, tiles)  # yields in order, as the tiles finish
        try:
            for rows, colours in done:
                image[rows] = colours
                bar.update()
        finally:
            if threads > 1:
                pool.shutdown(cancel_futures=True)
    return image


def _distributed_tile(world: World, scene: Scene, rows: slice, depth: int, spp: int,
                      seed: int, pixel_filter: str, rough: bool) -> np.ndarray:
    """The rows (R, W, 3) of a distributed render: spp samples per pixel, averaged, traced in
    chunks of whole pixels of at most TILE_RAYS rays (or one pixel).  Each dimension draws
    from its own generator, keyed by (seed, the tile's first row, dimension), so the samples
    depend on neither the threads nor which other effects are on."""
    W = scene.width
    first, pixels = rows.start * W, (rows.stop - rows.start) * W
    rngs = [np.random.default_rng([seed, rows.start, dim]) for dim in range(2 + depth)]
    colour = np.empty((pixels, 3))
    step = max(1, TILE_RAYS // spp)
    for start in range(0, pixels, step):
        n = min(step, pixels - start)
        offsets = pixel_offsets(stratified(rngs[0], n, spp, centre=True), pixel_filter)
        lens = concentric_disk(stratified(rngs[1], n, spp)) \
            if scene.camera.aperture > 0.0 else None
        o, d = sample_rays(scene.camera, W, scene.height, first + start + np.arange(n),
                           offsets, lens)
        glossy = [stratified(rng, n, spp).reshape(-1, 2) for rng in rngs[2:]] if rough \
            else None
        c = trace(world, scene, o, d, depth, None if glossy is None else glossy.__getitem__)
        colour[start:start + n] = c.reshape(n, spp, 3).mean(axis=1)
    return colour.reshape(-1, W, 3)


def aliasing_pair(scene: Scene, spp: int = 16, seed: int = 0, pixel_filter: str = "box",
                  **kwargs) -> tuple[np.ndarray, np.ndarray]:
    """The lecture's "aliasing through discrete sampling": `scene` rendered at one sample per
    pixel (the centre: the staircase) and at `spp` stratified samples (the edge's coverage),
    each (H, W, 3) float64; `kwargs` go to `render`."""
    return (render(scene, **kwargs),
            render(scene, spp=spp, seed=seed, pixel_filter=pixel_filter, **kwargs))
