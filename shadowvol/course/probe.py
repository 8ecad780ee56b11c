"""The count probe: why one pixel is (or is not) in shadow, face by face.

For pixel (x, y) and one light, `probe` follows the pixel's eye ray (from the near plane, as
the rasterizer clips) through every shadow-volume face the stencil pass draws for that light —
side quads with their multiplicity, near caps (every triangle, facing the light), far caps (every
triangle at infinity) — in order, each crossing with its +1 (entering the volume) or -1
(leaving), and sums them as the two methods do:

    z-pass = the side quads' steps in front of the visible point          (counted from the eye)
    z-fail = minus the steps of every face behind it, out to infinity     (counted from infinity)

Z-fail is the number of volumes around the visible point; z-pass is that minus the number
around the eye (so the two differ exactly when the eye stands in a volume).  The stencil the
renderer read back for the same pixel, and the ray tracer's shadow ray (every triangle between
the visible point and the light: every triangle casts), say the same, or `explain` says why not.

Everything is float64 world-space geometry, computed from the same silhouettes
(`raster.volumes.silhouettes`) the stencil pass extrudes; no GL here except the read-back the caller
passes in (`Renderer.render(stencil=True)`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from raytrace.camera import primary_rays
from raytrace.intersect import ray_triangle
from shadowvol.raster.volumes.silhouettes import edge_multiplicity, side_quads, topology_signs
from shadowvol.raster.volumes.topology import Topology

PARALLEL = 1e-12     # |n . d| / (|n| |d|) below which a ray runs inside a face's plane: no crossing


@dataclass(frozen=True)
class Crossing:
    """One volume face the eye ray crosses.

    t        : distance along the eye ray from its near-plane origin (inf: the far cap)
    kind     : "side", "near cap" or "far cap"
    object   : index of the caster in scene.objects
    entering : True when the ray enters the volume there (it sees the face's outside)
    copies   : how many times the stencil pass draws the face (a side's |multiplicity|)
    behind   : the face lies behind the visible point (z-fail counts it)
    """

    t: float
    kind: str
    object: int
    entering: bool
    copies: int
    behind: bool

    @property
    def step(self) -> int:
        """+copies entering, -copies leaving: the face's z-pass step."""
        return self.copies if self.entering else -self.copies


@dataclass(frozen=True)
class Probe:
    """The probe of one pixel for one light (see the module docstring).

    surface      : (3,) float64 visible point, or None (background)
    surface_tri  : index of the visible triangle in scene.triangles(), or -1
    crossings    : every crossing, in order of t
    zfail_casters: (n_objects,) bool, the casters the renderer counted with z-fail
    stencil      : the stencil the renderer read back at the pixel (None when not given)
    shadow_hits  : (k, 2) float64 array of (t, object) for every triangle the shadow ray from
                   the visible point to the light crosses, nearest first
    own          : 1 when the visible triangle faces away from the light (its own near cap is
                   counted at the visible point), else 0
    """

    pixel: tuple[int, int]
    light: int
    surface: np.ndarray | None
    surface_tri: int
    crossings: list[Crossing]
    zfail_casters: np.ndarray
    stencil: int | None = None
    shadow_hits: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    own: int = 0

    def zpass_sum(self, objects=None) -> int:
        return sum(c.step for c in self.crossings if c.kind == "side" and not c.behind
                   and (objects is None or c.object in objects))

    def zfail_sum(self, objects=None) -> int:
        return -sum(c.step for c in self.crossings if c.behind
                    and (objects is None or c.object in objects))

    @property
    def predicted(self) -> int:
        """The stencil the renderer's choice of method per caster gives."""
        zf = set(np.flatnonzero(self.zfail_casters).tolist())
        zp = set(range(len(self.zfail_casters))) - zf
        return self.zpass_sum(zp) + self.zfail_sum(zf)

    @property
    def eye_inside(self) -> int:
        """How many volumes (with multiplicity) hold the eye's near-plane point."""
        return self.zfail_sum() - self.zpass_sum()

    def explain(self, names=None) -> str:
        """The probe as text: every crossing with its step, the sums, the read-back, the
        shadow ray, and the verdict."""
        name = (lambda i: names[i]) if names is not None else (lambda i: f"object {i}")
        x, y = self.pixel
        lines = [f"pixel ({x}, {y}), light {self.light}: "
                 + ("background" if self.surface is None else
                    "visible point (" + ", ".join(f"{v:.3f}" for v in self.surface) + ")")]
        if self.crossings:
            lines.append("  t        face      of             step  *behind: z-fail")
        for c in self.crossings:
            t = "inf" if not np.isfinite(c.t) else f"{c.t:.4f}"
            lines.append(f"  {t:>8} {c.kind:9} {name(c.object)[:14]:14} "
                         f"{'in ' if c.entering else 'out'} {c.step:+d}"
                         + (f" *{-c.step:+d}" if c.behind else ""))
        zp, zf = self.zpass_sum(), self.zfail_sum()
        lines.append(f"z-pass sum {zp}, z-fail sum {zf}"
                     + (f", renderer's mix {self.predicted}" if self.zfail_casters.any()
                        and not self.zfail_casters.all() else ""))
        if self.stencil is not None:
            lines.append(f"stencil read back: {self.stencil}")
        if self.surface is not None:
            hits = ", ".join(name(int(o)) for _, o in self.shadow_hits) or "nothing"
            lines.append(f"shadow ray to the light crosses {len(self.shadow_hits)} "
                         f"triangle(s): {hits}" + (" (+1: the surface itself faces away "
                                                   "from the light)" if self.own else ""))
        if zp != zf:
            lines.append(f"z-pass is off by {zf - zp}: the eye (its near-plane point) stands "
                         f"in {self.eye_inside} volume(s), which z-pass never sees entered; "
                         "z-fail counts from infinity, where no volume reaches")
        ok = self.stencil is None or self.stencil == self.predicted
        ok &= self.surface is None or zf == len(self.shadow_hits) + self.own
        lines.append("all counts agree" if ok else "counts DISAGREE")
        return "\n".join(lines)


class Prober:
    """The volume faces of one scene for one light, ready to probe many pixels."""

    def __init__(self, scene, light: int, camera=None):
        self.scene = scene
        self.camera = scene.camera if camera is None else camera
        self.light_index = light
        self.light4 = scene.lights[light].homogeneous
        vertices, faces, ids = scene.triangles()
        self.tris = vertices[faces]                                      # (m, 3, 3)
        self.ids = ids
        sides, side_obj, side_copies = [], [], []
        signs = []
        for i, obj in enumerate(scene.objects):
            topo = Topology.build(obj.vertices, obj.faces)
            s = topology_signs(topo, self.light4)
            m = edge_multiplicity(topo, s)
            on = m != 0
            q = side_quads(topo, np.sign(m), self.light4)                # one quad per edge
            sides.append(q)
            side_obj.append(np.full(len(q), i))
            side_copies.append(np.abs(m[on]))
            # the topology's faces are the object's faces in order: signs per soup triangle
            signs.append(s)
        self.sides = np.concatenate(sides) if sides else np.zeros((0, 4, 4))
        self.side_obj = np.concatenate(side_obj).astype(int)
        self.side_copies = np.concatenate(side_copies).astype(int)
        self.signs = np.concatenate(signs).astype(int)
        e1 = self.tris[:, 1] - self.tris[:, 0]
        e2 = self.tris[:, 2] - self.tris[:, 0]
        self.normals = np.cross(e1, e2)                                  # as wound

    def probe(self, x: int, y: int, zfail_casters=None, stencil: int | None = None) -> Probe:
        scene, cam = self.scene, self.camera
        o, d = primary_rays(cam, scene.width, scene.height, rows=slice(y, y + 1))
        o, d = o[x], d[x]
        t_tri = ray_triangle(o[None], d[None], self.tris[:, 0], self.tris[:, 1],
                             self.tris[:, 2])
        hit = int(np.argmin(t_tri)) if np.isfinite(t_tri).any() else -1
        t_surf = float(t_tri[hit]) if hit >= 0 else np.inf
        crossings = []
        # side quads
        for k, t, entering in self._side_crossings(o, d):
            crossings.append(Crossing(t, "side", int(self.side_obj[k]), entering,
                                      int(self.side_copies[k]), t > t_surf))
        # near caps: every triangle that casts, outward normal toward the light
        cast = self.signs != 0
        for k in np.flatnonzero(cast & np.isfinite(t_tri)):
            n_out = self.signs[k] * self.normals[k]
            behind = bool(t_tri[k] > t_surf or k == hit)   # its own cap ties: "behind"
            crossings.append(Crossing(float(t_tri[k]), "near cap", int(self.ids[k]),
                                      bool(n_out @ d < 0), 1, behind))
        # far caps (point and spot lights): the ray ends inside the cone from L through T
        if self.light4[3] != 0.0:
            L = self.light4[:3] / self.light4[3]
            t_far = ray_triangle(L[None], d[None], self.tris[:, 0], self.tris[:, 1],
                                 self.tris[:, 2])
            for k in np.flatnonzero(cast & np.isfinite(t_far)):
                crossings.append(Crossing(np.inf, "far cap", int(self.ids[k]), False, 1, True))
        crossings.sort(key=lambda c: c.t)
        zfail = (np.zeros(len(scene.objects), bool) if zfail_casters is None
                 else np.asarray(zfail_casters, bool))
        if hit < 0:
            return Probe((x, y), self.light_index, None, -1, crossings, zfail, stencil)
        p = o + t_surf * d
        # the eye sees the side of the visible triangle that faces away from the light: its
        # own near cap, left at p, counts 1 there (it is unlit by n . l anyway)
        own = int(self.signs[hit] != 0 and (self.signs[hit] * self.normals[hit]) @ d > 0)
        return Probe((x, y), self.light_index, p, hit, crossings, zfail, stencil,
                     self._shadow_ray(p, hit), own)

    def _side_crossings(self, o: np.ndarray, d: np.ndarray):
        """(quad index, t, entering) of every side quad the ray o + t d (t > 0) crosses."""
        q = self.sides
        if not len(q):
            return []
        e, s = q[:, 0, :3], q[:, 1, :3]
        ds = q[:, 2, :3]                                   # s extruded: a direction (w = 0)
        n_out = np.cross(s - e, ds)                        # the quad's winding: out of the volume
        nd = n_out @ d
        ok = np.abs(nd) > PARALLEL * np.linalg.norm(n_out, axis=1) * np.linalg.norm(d)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.einsum("ij,ij->i", n_out, s - o) / nd
        X = o + t[:, None] * d
        u = e - s
        with np.errstate(divide="ignore", invalid="ignore"):
            if self.light4[3] != 0.0:
                # point light: X on the ray from L through S(a) = s + a u, beyond S(a):
                # (X - L) x (S(a) - L) = 0 gives a; X - L = mu (S(a) - L) with mu >= 1
                L = self.light4[:3] / self.light4[3]
                xl = X - L
                c1, c2 = np.cross(xl, s - L), np.cross(xl, u)
                a = -np.einsum("ij,ij->i", c1, c2) / np.einsum("ij,ij->i", c2, c2)
                S = s + a[:, None] * u
                mu = np.einsum("ij,ij->i", xl, S - L) / np.einsum("ij,ij->i", S - L, S - L)
                beyond = mu >= 1.0
            else:
                # directional light: X = s + a u + lam dir, lam >= 0 (the normal equations)
                w, v = X - s, ds
                uu, uv, vv = (np.einsum("ij,ij->i", p_, q_) for p_, q_ in
                              ((u, u), (u, v), (v, v)))
                wu, wv = np.einsum("ij,ij->i", w, u), np.einsum("ij,ij->i", w, v)
                det = uu * vv - uv * uv
                a = (wu * vv - wv * uv) / det
                beyond = (wv * uu - wu * uv) / det >= 0.0
        inside = ok & (t > 0) & (a >= 0.0) & (a <= 1.0) & beyond
        return [(int(k), float(t[k]), bool(nd[k] < 0)) for k in np.flatnonzero(inside)]

    def _shadow_ray(self, p: np.ndarray, own_tri: int) -> np.ndarray:
        """(k, 2): (t, object) of every triangle between `p` (on triangle `own_tri`) and the
        light, nearest first."""
        L4 = self.light4
        to = L4[:3] - L4[3] * p
        dist = np.linalg.norm(to) if L4[3] else np.inf
        direction = to / np.linalg.norm(to)
        t = ray_triangle(p[None], direction[None], self.tris[:, 0], self.tris[:, 1],
                         self.tris[:, 2])
        t[own_tri] = np.inf
        between = np.flatnonzero(t < (dist if np.isfinite(dist) else np.inf))
        order = between[np.argsort(t[between])]
        hits = np.stack([t[order], self.ids[order].astype(float)], axis=1) if len(order) \
            else np.zeros((0, 2))
        return hits


def probe(renderer, x: int, y: int, light: int = 0, method: str = "auto", camera=None,
          lights=None) -> Probe:
    """The probe of pixel (x, y) for `light` in `renderer`'s scene, with the stencil the
    renderer reads back for the same frame (method, camera, lights)."""
    scene = renderer.scene
    lights = scene.lights if lights is None else tuple(lights)
    frame = renderer.render(method, camera=camera, lights=lights, stencil=True)
    prober = Prober(scene.replace(lights=lights), light, camera)
    return prober.probe(x, y, frame.zfail[light], int(frame.stencil[light, y, x]))
