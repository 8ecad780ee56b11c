"""Radiosity (Goral et al. 1984) on the scene's triangles: meshing, ray-cast form factors,
progressive refinement (Cohen et al. 1988), display from the camera.

Units: everything is radiance, L = B / pi (a Lambertian surface's radiosity B = pi L), so that
the system is the diffuse rendering equation discretised over patches,

    L_i = E_i + rho_i · sum_j F_ij L_j ,

with E_i the material's `emission` and rho_i its diffuse albedo (the normalised Phong kd of
`raytrace.outlook.brdf`; specular, mirror and glass terms are dropped: radiosity is the diffuse
part).

Patches.  First, where an edge of one surface lies on another's plane (a block on the floor), the
lower triangle is cut along that edge's line (`raytrace.outlook.contacts`): a patch running under a
block would average its lit part with the buried one, and the blocks came out 1-2 % dark at every
level and seed.  Then every triangle is split by midpoints into 4^k similar triangles, k the
smallest making its longest edge at most  (the scene's longest triangle edge) / 2^level. Surfaces
are two-sided, so each triangle has two patches, one per face: patch `t` is the face its winding
normal points out of, patch `t + T` the other (T triangles).  A face that sees nothing (the outside
of a wall) simply stays dark.

Form factors by ray casting (Malley's method): from each patch, `rays_per_patch` rays leave
stratified points of it in cosine-distributed directions (`raytrace.outlook.formrays`: stratified
over the square, a quarter of them in a window around the emitters, each ray weighted so that a
patch's weights sum to 1), and are traced through Embree; F_ij is the weight of the rays whose first
hit is patch j (the face hit is the one facing the ray).  This estimates the area-to-area form
factor with visibility, unbiased; sum_j F_ij <= 1 exactly (1 minus the escaping rays: exactly 1 in a
closed box), reciprocity A_i F_ij = A_j F_ji holds in expectation only.  F is stored sparse (CSR),
at most rays_per_patch entries a row.  The defaults (level 3, 4096 rays) put every object of the
Cornell box within 1 % of the path tracer (docs/course.md).

Solver: progressive refinement by shooting (Cohen et al. 1988).  Each iteration shoots the
unshot radiance of the `shots` patches holding the most unshot power (A_i · ΔL_i, summed over
channels) to every patch j that sees them: ΔL_j += rho_j F_ji ΔL_i.  Cohen et al. get the
receiver's form factor F_ji from the shooter's hemicube by reciprocity, F_ij A_i / A_j; here all
rows are cast first, so F_ji is j's own estimate (column i of F), and shooting is exactly
Southwell relaxation of the gathering system above: it converges to that system's solution even
though ray-cast form factors are reciprocal only on average (with the reciprocity form, a
furnace box would come out blotchy instead of uniform).  It stops when the unshot power is at
most `tol` times the emitted power (or after `max_iterations`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from shadowvol.errors import require

if TYPE_CHECKING:
    import scipy.sparse as sp
from shadowvol.scene import Scene

from raytrace.backends import make_backend
from raytrace.camera import primary_rays
from raytrace.intersect import dot
from raytrace.tolerances import surface_offset

from .brdf import around, normalised_phong
from .contacts import sides, split_at_contacts
from .formrays import concentric_disk, emitter_windows, ray_square_points, stratified

DEFAULT_LEVEL = 3
DEFAULT_RAYS_PER_PATCH = 4096  # per wall within 2 % of the path tracer (docs/course.md)
DEFAULT_TOL = 1e-4  # unshot power / emitted power at which shooting stops
MAX_SUBDIVISION = 12  # 4^12 children per triangle is already absurd: a guard against bad input
RAY_CHUNK = 1 << 18  # form-factor rays traced per call (bounds memory: ~100 bytes a ray)
# Interpolated display: patch corners are the same vertex when their positions agree to this
# fraction of the largest coordinate (midpoint subdivision computes shared corners identically,
# up to rounding) and their face normals to this much per component.
WELD_RELATIVE = 1e-7
NORMAL_QUANTUM = 1e-4


@dataclass(frozen=True, eq=False)
class PatchMesh:
    """The scene's triangles, subdivided.

    vertices : (V, 3) float64;  faces : (T, 3) int64 (one patch per face of each triangle, 2T
    patches);  tri_object : (T,) int, the object of each triangle;  area : (T,) float64; normal :
    (T, 3) float64 unit winding normals;  contacts : (C, 3, 3) the contact segments the mesh was cut
    along (`raytrace.outlook.contacts`), which the interpolated display never blends across.
    """

    vertices: np.ndarray
    faces: np.ndarray
    tri_object: np.ndarray
    area: np.ndarray
    normal: np.ndarray
    contacts: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 3)))

    @property
    def triangles(self) -> int:
        return len(self.faces)

    @property
    def patches(self) -> int:
        return 2 * len(self.faces)

    def patch_normal(self) -> np.ndarray:
        """(2T, 3) the outward normal of each patch's face."""
        return np.concatenate([self.normal, -self.normal])

    def patch_area(self) -> np.ndarray:
        return np.concatenate([self.area, self.area])

    def patch_object(self) -> np.ndarray:
        return np.concatenate([self.tri_object, self.tri_object])


def split_triangles(corners: np.ndarray) -> np.ndarray:
    """(n, 3, 3) triangles -> (4n, 3, 3), each split at its edge midpoints."""
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
    return np.stack([np.stack(t, axis=1) for t in
                     ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))], axis=1).reshape(-1, 3, 3)


def mesh_patches(scene: Scene, level: int = DEFAULT_LEVEL, max_edge: float | None = None,
                 contacts: bool = True) -> PatchMesh:
    """Subdivide the scene's triangles (see the module docstring); `level` >= 0, or, given,
    `max_edge` (scene units, > 0) the longest edge allowed instead of longest / 2^level (the
    scene's own longest edge, before the contact cuts: `raytrace.outlook.contacts`, unless
    contacts=False)."""
    if isinstance(level, bool) or not isinstance(level, (int, np.integer)) or level < 0:
        raise ValueError(f"level must be a whole number >= 0, got {level!r}")
    vertices, faces, ids = scene.triangles()
    corners = vertices[faces]
    edges = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).max(axis=1)
    target = edges.max() / 2.0 ** level if max_edge is None else float(max_edge)
    if not target > 0.0:
        raise ValueError(f"max_edge must be > 0, got {max_edge!r}")
    segments = np.zeros((0, 3, 3))
    if contacts:
        corners, ids, segments = split_at_contacts(corners, ids)
        edges = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).max(axis=1)
    splits = np.ceil(np.log2(np.maximum(edges / target, 1.0)) - 1e-9).astype(int)
    if splits.max() > MAX_SUBDIVISION:
        raise ValueError(f"level {level} would split a triangle 4^{splits.max()} ways")
    out_corners, out_ids = [], []
    for k in range(splits.max() + 1):
        sel = splits == k
        c = corners[sel]
        for _ in range(k):
            c = split_triangles(c)
        out_corners.append(c)
        out_ids.append(np.repeat(ids[sel], 4 ** k))
    c = np.concatenate(out_corners)
    cross = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
    length = np.linalg.norm(cross, axis=1)
    keep = length > 0.0
    c, cross, length = c[keep], cross[keep], length[keep]
    return PatchMesh(c.reshape(-1, 3), np.arange(3 * len(c)).reshape(-1, 3),
                     np.concatenate(out_ids)[keep], 0.5 * length, cross / length[:, None],
                     segments)


def form_factors(scene: Scene, mesh: PatchMesh, rays_per_patch: int = DEFAULT_RAYS_PER_PATCH,
                 seed: int = 0, backend: str = "embree") -> tuple[sp.csr_matrix, int]:
    """F (2T, 2T) CSR float64, F[i, j] = the weighted share of patch i's rays whose first hit
    is patch j (`raytrace.outlook.formrays`: stratified, a share aimed at the emitters, weights
    summing to 1 a patch); and the number of rays traced."""
    rng = np.random.default_rng(seed)
    tracer = make_backend(backend, mesh.vertices, mesh.faces)
    T, P = mesh.triangles, mesh.patches
    offset = surface_offset(scene)
    normals = mesh.patch_normal()
    emitters = emitter_corners(scene)
    emits = np.array([o.material.emission.any() for o in scene.objects])[mesh.patch_object()]
    sp = _sparse()
    blocks = []  # one CSR block of rows a chunk, duplicates summed: memory ~ nonzeros, not rays
    per_chunk = max(1, RAY_CHUNK // rays_per_patch)
    for first in range(0, P, per_chunk):
        ids = np.arange(first, min(first + per_chunk, P))
        c = mesh.vertices[mesh.faces[ids % T]]
        window = emitter_windows(c, normals[ids], emitters, emits[ids])
        u, v, weight = ray_square_points(rng, window, rays_per_patch)
        o1, o2 = stratified(rng, len(ids), rays_per_patch)
        r = np.sqrt(o1)[..., None]
        x = ((1.0 - r) * c[:, None, 0] + r * (1.0 - o2[..., None]) * c[:, None, 1]
             + r * o2[..., None] * c[:, None, 2]).reshape(-1, 3)
        patch = np.repeat(ids, rays_per_patch)
        n = normals[patch]
        radius, phi = concentric_disk(u.ravel(), v.ravel())
        d = around(n, np.sqrt(np.maximum(1.0 - radius * radius, 0.0)), phi)
        hits = tracer.closest_hit(x + offset * n, d)
        h = hits.tri >= 0
        facing_back = dot(tracer.normals[hits.tri[h]], d[h]) > 0.0  # the ray meets the -n face
        block = sp.csr_matrix((weight.ravel()[h], (patch[h] - first,
                                                   hits.tri[h] + np.where(facing_back, T, 0))),
                              shape=(len(ids), P))
        block.sum_duplicates()
        blocks.append(block)
    F = sp.vstack(blocks, format="csr")
    F.sum_duplicates()
    return F, P * rays_per_patch


def emitter_corners(scene: Scene) -> np.ndarray:
    """(8 e, 3) the corners of each emissive object's bounding box: what the rays aim at."""
    boxes = [(o.vertices.min(axis=0), o.vertices.max(axis=0)) for o in scene.objects
             if o.material.emission.any()]
    return np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]] for lo, hi in boxes
                     for i in (0, 1) for j in (0, 1) for k in (0, 1)]).reshape(-1, 3)


@dataclass(frozen=True, eq=False)
class Solution:
    """radiance : (2T, 3) float64 per patch;  iterations, shots;  unshot : the unshot power left
    over the emitted power;  seconds of (form factors, solve);  rays traced for F."""

    mesh: PatchMesh
    radiance: np.ndarray
    iterations: int
    shots: int
    unshot: float
    form_factor_seconds: float
    solve_seconds: float
    rays: int


def shoot(F: sp.csr_matrix, area: np.ndarray, rho: np.ndarray, emission: np.ndarray,
          tol: float = DEFAULT_TOL, shots: int = 1, max_iterations: int | None = None
          ) -> tuple[np.ndarray, int, float]:
    """Progressive refinement: radiance (P, 3), iterations, remaining unshot / emitted power.
    F (P, P) sparse; area (P,); rho, emission (P, 3)."""
    L = emission.astype(np.float64).copy()
    unshot = L.copy()
    emitted = float((area[:, None] * emission).sum())
    if emitted == 0.0:
        return L, 0, 0.0
    power = area * unshot.sum(axis=1)
    shots = min(max(1, int(shots)), len(area))  # more than every patch at once: every patch
    limit = max_iterations if max_iterations is not None else 1000 * len(area) // shots + 1000
    columns = _sparse().csc_matrix(F)  # column i: F_ji for every receiver j
    indptr, indices, data = columns.indptr, columns.indices, columns.data
    it = 0
    left = float(power.sum()) / emitted
    while left > tol and it < limit:
        if shots == 1:
            i = int(np.argmax(power))
            js = indices[indptr[i]:indptr[i + 1]]
            gain = data[indptr[i]:indptr[i + 1], None] * rho[js] * unshot[i]
            unshot[i] = 0.0
            power[i] = 0.0
        else:
            top = np.argpartition(power, -shots)[-shots:]
            sub = columns[:, top].tocsr()
            js = np.flatnonzero(np.diff(sub.indptr))
            gain = rho[js] * (sub[js] @ unshot[top])
            unshot[top] = 0.0
            power[top] = 0.0
        L[js] += gain
        unshot[js] += gain
        power[js] = area[js] * unshot[js].sum(axis=1)
        it += 1
        left = float(power.sum()) / emitted
    return L, it, left


def solve(scene: Scene, level: int = DEFAULT_LEVEL, rays_per_patch: int = DEFAULT_RAYS_PER_PATCH,
          tol: float = DEFAULT_TOL, shots: int = 1, seed: int = 0, backend: str = "embree",
          mesh: PatchMesh | None = None) -> Solution:
    """Mesh, form factors, progressive refinement: the radiosity solution of `scene`."""
    mesh = mesh_patches(scene, level) if mesh is None else mesh
    t0 = time.perf_counter()
    F, rays = form_factors(scene, mesh, rays_per_patch, seed, backend)
    t1 = time.perf_counter()
    kd, _ = normalised_phong(np.array([o.material.diffuse for o in scene.objects]),
                             np.array([o.material.specular for o in scene.objects]))
    emission = np.array([o.material.emission for o in scene.objects])
    obj = mesh.patch_object()
    L, iterations, left = shoot(F, mesh.patch_area(), kd[obj], emission[obj], tol, shots)
    t2 = time.perf_counter()
    shots = min(max(1, int(shots)), mesh.patches)  # as `shoot` shoots them
    return Solution(mesh, L, iterations, iterations * shots, left, t1 - t0,
                    t2 - t1, rays)


def vertex_radiance(mesh: PatchMesh, radiance: np.ndarray) -> np.ndarray:
    """(2T, 3 corners, 3) radiance at each patch's corners for interpolated display: the
    area-weighted mean over the patches that share the corner's position, object, face
    orientation and side of any contact through it (so that light never leaks round an edge
    onto another wall, nor out from under a block)."""
    T = mesh.triangles
    scale = max(float(np.abs(mesh.vertices).max()), 1e-300)
    pos = np.round(mesh.vertices[mesh.faces] / (scale * WELD_RELATIVE)).astype(np.int64)
    nrm = np.round(mesh.normal / NORMAL_QUANTUM).astype(np.int64)
    corners = mesh.vertices[mesh.faces]
    side = sides(corners.reshape(-1, 3), np.repeat(corners.mean(axis=1), 3, axis=0),
                 mesh.contacts).reshape(T, 3, 1)
    key = np.concatenate([
        np.concatenate([pos, np.broadcast_to(nrm[:, None], (T, 3, 3)),
                        np.broadcast_to(mesh.tri_object[:, None, None], (T, 3, 1)), side],
                       axis=2),
        np.concatenate([pos, np.broadcast_to(-nrm[:, None], (T, 3, 3)),
                        np.broadcast_to(mesh.tri_object[:, None, None], (T, 3, 1)), side],
                       axis=2)])
    _, group = np.unique(key.reshape(-1, 8), axis=0, return_inverse=True)
    group = group.ravel()
    w = np.repeat(mesh.patch_area(), 3)
    vals = np.repeat(radiance, 3, axis=0)
    sums = np.stack([np.bincount(group, weights=w * vals[:, c]) for c in range(3)], axis=1)
    weight = np.bincount(group, weights=w)
    return (sums / weight[:, None])[group].reshape(-1, 3, 3)


def display(scene: Scene, solution: Solution, interpolate: bool = True,
            backend: str = "embree") -> np.ndarray:
    """The solution seen from the camera: (H, W, 3) float64 linear radiance, pixel centres;
    flat (each patch its constant) or interpolated (barycentric blend of `vertex_radiance`)."""
    mesh = solution.mesh
    tracer = make_backend(backend, mesh.vertices, mesh.faces)
    o, d = primary_rays(scene.camera, scene.width, scene.height)
    hits = tracer.closest_hit(o, d)
    image = np.tile(scene.background, (len(o), 1)).astype(np.float64)
    h = np.flatnonzero(hits.tri >= 0)
    tri = hits.tri[h]
    back = dot(tracer.normals[tri], d[h]) > 0.0
    patch = tri + np.where(back, mesh.triangles, 0)
    if not interpolate:
        image[h] = solution.radiance[patch]
    else:
        corners = vertex_radiance(mesh, solution.radiance)[patch]
        p = o[h] + hits.t[h, None] * d[h]
        c = mesh.vertices[mesh.faces[tri]]
        e1, e2, q = c[:, 1] - c[:, 0], c[:, 2] - c[:, 0], p - c[:, 0]
        d11, d12, d22 = dot(e1, e1), dot(e1, e2), dot(e2, e2)
        q1, q2 = dot(q, e1), dot(q, e2)
        den = d11 * d22 - d12 * d12
        v = np.clip((d22 * q1 - d12 * q2) / den, 0.0, 1.0)
        w = np.clip((d11 * q2 - d12 * q1) / den, 0.0, 1.0)
        u = np.clip(1.0 - v - w, 0.0, 1.0)
        image[h] = (u[:, None] * corners[:, 0] + v[:, None] * corners[:, 1]
                    + w[:, None] * corners[:, 2])
    return image.reshape(scene.height, scene.width, 3)


def summary(solution: Solution) -> str:
    """One line for people: patches, iterations, time."""
    m = solution.mesh
    return (f"{m.triangles} triangles ({m.patches} patches, two faces each), "
            f"{solution.rays / 1e6:.2f} M form-factor rays in {solution.form_factor_seconds:.2f} s, "
            f"{solution.iterations} iterations ({solution.shots} shots) in "
            f"{solution.solve_seconds:.2f} s, unshot power {solution.unshot:.1e} of emitted")


def _sparse():
    """scipy.sparse, the one optional package radiosity needs (the [outlook] extra)."""
    return require("scipy.sparse", "raytrace radiosity", extra="outlook", package="scipy")
