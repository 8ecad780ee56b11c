"""The path tracer's state: its precision, and the scene as the path tracer sees it.

Shared by the numpy shading (`raytrace.outlook.path.pathtrace`) and the compiled one
(`raytrace.outlook.path.pathkernels`), which must agree bit for bit: the float32 of the state
(`STATE`), the one division guard, the roulette's bound and the packed tables of `PathWorld` are
defined once, here.
"""

from __future__ import annotations

import numpy as np

from shadowvol.scene import Scene, hard_lights

from raytrace.backends import make_backend
from raytrace.outlook.brdf import diffuse_probability, normalised_phong
from raytrace.texture import SurfaceColours
from raytrace.tolerances import surface_offset

RR_MAX_SURVIVAL = 0.95  # never certain survival: bounds the expected path length
# The path state's precision (rays, hit points, throughputs, the tables; see
# `raytrace.outlook.path.pathtrace`) and the smallest value a float32 division is kept from dividing
# by.
STATE = np.float32
STATE_TINY = 1e-30


def take(a: np.ndarray, index: np.ndarray) -> np.ndarray:
    """Columns `index` of a (3, k) array, or entries of a (k,) one (np.take: a fancy index on
    the last axis of a (3, k) array is several times slower)."""
    return np.take(a, index, axis=-1)


class PathWorld:
    """The scene as the path tracer and radiosity see it: all objects' triangles in one backend,
    per-object material arrays, the same per triangle, and the emitters to sample.

    tri_object : (M,) int, the object of each triangle;  area : (M,) float64
    kd, ks : (K, 3) normalised Phong (`brdf.normalised_phong`);  shininess, refl, transp, ior,
    p_diffuse : (K,);  emission : (K, 3)
    emitters : (E,) int, emissive triangles;  emitter_cdf : (E,) float64, cumulative choice
    probability (area x mean emission)
    The tracer's own tables, vectors as rows: per triangle (`surface`) and per emitter
    (`sample_emitters`), each packed into one small (P, M) array, so that what a hit needs is
    one gather by triangle, no per-object indirection; tri_emission (3, M).
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
        # textures and vertex colours (None: none in the scene): `textured_kd`
        self.surface_colours = SurfaceColours.of(scene)
        self.tri_first = np.cumsum([0] + [len(o.faces) for o in scene.objects])[:-1]
        power = self.area * self.emission[self.tri_object].mean(axis=1)
        self.emitters = np.flatnonzero(power > 0.0)
        self.emitter_cdf = np.cumsum(power[self.emitters]) / max(power.sum(), 1e-300)
        self.emitter_prob = power[self.emitters] / max(power.sum(), 1e-300)
        # p_A(y) of `sample_emitters` for a point on each triangle (0 off the emitters)
        self.light_pdf_area = np.zeros(len(self.area))
        self.light_pdf_area[self.emitters] = self.emitter_prob / self.area[self.emitters]
        # an area light of `scene.lights` is its samples (as in `raytrace.outlook.whitted`)
        self.lights = tuple(hard for lt in scene.lights for hard in hard_lights(lt))
        # per triangle, one packed table (rows: `surface`), only the rows this scene needs
        ob = self.tri_object
        tri_emission = self.emission[ob]
        self.tri_emits = self.light_pdf_area > 0.0
        self.any_glossy = bool((self.ks[ob] > 0.0).any())
        self.any_delta = bool((self.refl[ob] > 0.0).any() or (self.transp[ob] > 0.0).any())
        self.any_emits = bool(self.tri_emits.any())
        table = [("normal", self.tracer.normals.T), ("plane_d", self.tracer.plane_d),
                 ("kd", self.kd[ob].T)]
        if self.any_glossy:
            table += [("ks", self.ks[ob].T), ("shininess", self.shininess[ob]),
                      ("p_diffuse", self.p_diffuse[ob]),
                      ("glossy", self.ks[ob].max(axis=1) > 0.0)]
        if self.any_delta:
            table += [("phong", 1.0 - self.refl[ob] - self.transp[ob]),
                      ("refl", self.refl[ob]), ("transp", self.transp[ob]),
                      ("ior", self.ior[ob])]
        if self.any_emits:
            table += [("emits", self.tri_emits), ("light_pdf", self.light_pdf_area)]
        self._tri_table, self._tri_rows = pack(table)
        self.tri_emission = np.ascontiguousarray(tri_emission.T, STATE)
        # per emitter: a corner, two edges, the normal, the radiance, p_A of a point on it
        e = self.emitters
        c = self.corners[e]
        self._emitter_table, self._emitter_rows = pack([
            ("a", c[:, 0].T), ("ab", (c[:, 1] - c[:, 0]).T), ("ac", (c[:, 2] - c[:, 0]).T),
            ("normal", self.tracer.normals[e].T), ("radiance", tri_emission[e].T),
            ("pdf_area", self.emitter_prob / self.area[e] if len(e) else np.zeros(0))],
            constants=True)  # one rect light: the normal, radiance and density are constants

    def surface(self, tri: np.ndarray) -> dict:
        """What the path tracer needs of triangles tri (k,) int (>= 0), from one gather:
        normal (3, k) by winding, plane_d (k,), kd (3, k); ks (3, k), shininess, p_diffuse (k,)
        if the scene has a glossy material (else None, None, 1.0), and glossy (m,), the indices
        of those with a glossy lobe (`brdf.phong_eval_rows`); phong (the Phong lobes'
        weight), refl, transp, ior (k,) if it has a mirror or glass (else 1.0, None, None,
        None); emits (k,) bool and light_pdf (k,), `light_pdf_area`, if it has emitters (else
        None).  Vectors and numbers are `STATE`."""
        rows = unpack(np.take(self._tri_table, tri, axis=1), self._tri_rows)
        rows.setdefault("ks", None)
        rows.setdefault("shininess", None)
        rows.setdefault("p_diffuse", 1.0)
        rows.setdefault("phong", 1.0)
        for name in ("refl", "transp", "ior"):
            rows.setdefault(name, None)
        rows["emits"] = rows["emits"] > 0.0 if "emits" in rows else None
        rows["glossy"] = np.flatnonzero(rows["glossy"]) if "glossy" in rows else \
            np.zeros(0, np.int64)
        return rows

    def textured_kd(self, kd: np.ndarray, tri: np.ndarray, p: np.ndarray) -> np.ndarray:
        """kd (3, k) of hits on triangles tri (k,) at points p (3, k), times their base colour
        (`raytrace.texture`: textures and vertex colours; the hit's barycentrics from its
        `STATE` point, in float64); kd itself where the scene has neither."""
        if self.surface_colours is None:
            return kd
        obj = self.tri_object[tri]
        base = self.surface_colours.colour(obj, tri - self.tri_first[obj],
                                           np.asarray(p, np.float64).T)
        return (kd * base.T).astype(STATE)

    def intersect(self, o: np.ndarray, d: np.ndarray):
        """Closest hits of rays o, d (n, 3) float64: t (n,) (inf: miss), tri (n,) int (-1: miss),
        and the geometric normals (n, 3) by winding (zero for a miss)."""
        hits = self.tracer.closest_hit(o, d, parallel=self.parallel)
        normal = np.zeros((len(o), 3))
        h = hits.tri >= 0
        normal[h] = self.tracer.normals[hits.tri[h]]
        return hits.t, hits.tri, normal

    def closest_rows(self, o: np.ndarray, d: np.ndarray) -> np.ndarray:
        """The triangle (k,) int64 (-1: miss) that rays o, d (3, k) float64 hit first (float32
        in Embree, as every backend traces)."""
        return self.tracer.closest_triangle(o.T, d.T, parallel=self.parallel)

    def occluded(self, o: np.ndarray, d: np.ndarray, tmax) -> np.ndarray:
        return self.tracer.occluded(o, d, tmax, parallel=self.parallel)

    def occluded_rows(self, o: np.ndarray, d: np.ndarray, tmax) -> np.ndarray:
        """`occluded` for rays o, d (3, k)."""
        return self.tracer.occluded(o.T, d.T, tmax, parallel=self.parallel)

    def sample_emitters(self, rng: np.random.Generator, k: int, u=None):
        """k points on the emitters: y (3, k), the emitters' unit normals (3, k) by winding
        and radiance (3, k), and p_A(y) (k,), the area density of the choice (each of the last
        three (3, 1) or (1,) where it is the same on all emitters).  u: the uniforms (r
        float64 choosing the emitter, u1, u2 `STATE` the point in it, (k,) each) instead of
        drawing them from rng."""
        r, u1, u2 = (rng.random(k), rng.random(k, dtype=STATE),
                     rng.random(k, dtype=STATE)) if u is None else u
        j = np.minimum(np.searchsorted(self.emitter_cdf, r, side="right"),
                       len(self.emitters) - 1)
        r = np.sqrt(u1)
        e = unpack(np.take(self._emitter_table, j, axis=1) if len(self._emitter_table)
                    else self._emitter_table, self._emitter_rows)
        y = e["a"] + (r * (1.0 - u2)) * e["ab"] + (r * u2) * e["ac"]
        return y, e["normal"], e["radiance"], e["pdf_area"]


def pack(columns, constants: bool = False) -> tuple[np.ndarray, dict]:
    """Rows (n,) or (m, n) stacked into one (P, n) `STATE` table, and each name's row slice.
    constants: an entry equal for all n items is left out of the table and kept as a (m, 1) or
    (1,) array, to broadcast instead of being gathered (only for callers that never index a
    gathered entry themselves)."""
    rows, slices, at = [], {}, 0
    for name, value in columns:
        value = np.atleast_2d(np.asarray(value, np.float64)).astype(STATE)
        if constants and value.shape[1] and (value == value[:, :1]).all():
            slices[name] = value[:, :1] if len(value) > 1 else value[0, :1]
            continue
        rows.append(value)
        slices[name] = slice(at, at + len(value)) if len(value) > 1 else at
        at += len(value)
    table = np.concatenate(rows) if rows else np.zeros((0, 0), STATE)
    return np.ascontiguousarray(table), slices


def unpack(table: np.ndarray, slices: dict) -> dict:
    return {name: s if isinstance(s, np.ndarray) else table[s] for name, s in slices.items()}
