"""A photon map (Jensen 1996): stored photons, their k-d tree, and the density estimate.

The look-up is scipy's `cKDTree` (scipy is the `outlook` extra; `shadowvol.errors.require`
names the pip command where it is missing), not a tree of our own.

The estimate at a point x with unit normal n (facing the viewer) is the flux arriving per unit
area, E(x) = sum_p w_p Phi_p / (c pi r^2), over the photons p near x whose stored normal agrees
with n (`NORMAL_AGREEMENT`: a photon on the back of a thin wall, or on the other face of a
corner, is not light arriving at x):

* k nearest neighbours: r is the distance to the k-th photon, and the sum runs over the k - 1
  inside it.  For a uniform density the k - 1 photons within the k-th distance are uniform in
  the disc and E[(k - 1) / (pi r_k^2)] is the density itself; summing all k overestimates by
  k / (k - 1).
* a fixed radius r: every photon within r.
* kernels: "uniform" (w = 1, c = 1) or Jensen's "cone" (w = 1 - d / r, c = 1/3, so that the
  weights integrate to the disc's area).

The radiance a Lambertian surface sends is kd / pi times E; each photon's power already carries
the 1 / (photons shot) of its light (`raytrace.outlook.photon.share`).  The known bias of density
estimation -- the disc straddles an edge or a change of illumination -- shrinks with r, i.e.
as photons grow for a fixed k or as the radius shrinks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shadowvol.errors import require

KERNELS = ("cone", "uniform")
KERNEL_NORM = {"uniform": 1.0, "cone": 1.0 / 3.0}  # c above: sum of weights / (pi r^2)
NORMAL_AGREEMENT = 0.9  # cos of the largest angle between a photon's normal and the query's
PAIR_BUDGET = 1 << 20  # (query, photon) pairs per k-d tree call: bounds its arrays (~25 MB)


def kdtree():
    """scipy.spatial.cKDTree, or MissingExtra (exit status 2) naming the pip command."""
    spatial = require("scipy.spatial", "the photon map (raytrace --integrator photon)",
                      "outlook", "scipy")
    return spatial.cKDTree


@dataclass(frozen=True, eq=False)
class PhotonMap:
    """Photons stored at diffuse hits.

    position : (n, 3) float64;  normal : (n, 3) float64, unit, the side the photon arrived on;
    power : (n, 3) float64, each photon's flux (already divided by the photons shot);
    direction : (n, 3) float64, unit, the way it travelled (zero where not recorded);
    tree : the cKDTree of `position`, or None for an empty map
    """

    position: np.ndarray
    normal: np.ndarray
    power: np.ndarray
    direction: np.ndarray
    tree: object

    @classmethod
    def build(cls, position, normal, power, direction=None) -> "PhotonMap":
        position = np.asarray(position, np.float64).reshape(-1, 3)
        tree = kdtree()(position) if len(position) else None
        direction = np.zeros_like(position) if direction is None else \
            np.asarray(direction, np.float64).reshape(-1, 3)
        return cls(position, np.asarray(normal, np.float64).reshape(-1, 3),
                   np.asarray(power, np.float64).reshape(-1, 3), direction, tree)

    def __len__(self) -> int:
        return len(self.position)

    def irradiance(self, points: np.ndarray, normals: np.ndarray, k: int | None = None,
                   radius: float | None = None, kernel: str = "cone", brdf=None) -> np.ndarray:
        """The density estimate E (m, 3) float64 at points (m, 3) with unit normals (m, 3)
        (the module docstring); exactly one of k (>= 2) and radius (> 0).  brdf: None, or
        f(q, j) -> (P, 3), the BRDF for query points q (P,) int and photons j (P,) int, each
        photon weighted by it: then the result is the reflected radiance."""
        points = np.asarray(points, np.float64).reshape(-1, 3)
        normals = np.asarray(normals, np.float64).reshape(-1, 3)
        out = np.zeros((len(points), 3))
        if self.tree is None or not len(points):
            return out
        if radius is None:
            step = max(1, PAIR_BUDGET // min(k, len(self)))
            blocks = [slice(s, s + step) for s in range(0, len(points), step)]
        else:
            blocks = self._blocks(points, radius)
        for block in blocks:
            f = None if brdf is None else \
                (lambda q, j, first=block.start: brdf(q + first, j))
            if radius is None:
                out[block] = self._nearest(points[block], normals[block], k, kernel, f)
            else:
                out[block] = self._within(points[block], normals[block], radius, kernel, f)
        return out

    def _blocks(self, points: np.ndarray, radius: float) -> list[slice]:
        """Runs of query points with about `PAIR_BUDGET` photons within radius in all (a
        radius as large as the scene pairs every point with every photon)."""
        found = self.tree.query_ball_point(points, radius, return_length=True)
        ends = np.cumsum(found)
        cuts = np.searchsorted(ends, np.arange(PAIR_BUDGET, ends[-1], PAIR_BUDGET), "right")
        edges = np.unique(np.concatenate([[0], cuts, [len(points)]]))
        return [slice(a, b) for a, b in zip(edges[:-1], edges[1:])]

    def _nearest(self, points, normals, k: int, kernel: str, brdf) -> np.ndarray:
        k = min(k, len(self))
        dist, idx = self.tree.query(points, k=k)
        dist, idx = dist.reshape(len(points), k), idx.reshape(len(points), k)
        r = dist[:, -1]  # the k-th photon's distance; the sum runs over the k - 1 inside
        inner, d = idx[:, :-1], dist[:, :-1]
        if k == 1:
            return np.zeros((len(points), 3))
        w = _weights(d, r[:, None], kernel)
        w *= np.einsum("mkc,mc->mk", self.normal[inner], normals) > NORMAL_AGREEMENT
        power = self.power[inner]
        if brdf is not None:
            m = len(points)
            power = power * brdf(np.repeat(np.arange(m), k - 1), inner.ravel()).reshape(
                m, k - 1, 3)
        flux = np.einsum("mk,mkc->mc", w, power)
        with np.errstate(divide="ignore", invalid="ignore"):
            e = flux / (KERNEL_NORM[kernel] * np.pi * r[:, None] ** 2)
        return np.where(np.isfinite(e), e, 0.0)

    def _within(self, points, normals, radius: float, kernel: str, brdf) -> np.ndarray:
        pairs = kdtree()(points).sparse_distance_matrix(self.tree, radius,
                                                         output_type="ndarray")
        i, j, d = pairs["i"], pairs["j"], pairs["v"]
        w = _weights(d, radius, kernel)
        w *= (self.normal[j] * normals[i]).sum(axis=1) > NORMAL_AGREEMENT
        power = self.power[j] if brdf is None else self.power[j] * brdf(i, j)
        flux = np.stack([np.bincount(i, w * power[:, c], minlength=len(points))
                         for c in range(3)], axis=1)
        return flux / (KERNEL_NORM[kernel] * np.pi * radius ** 2)


def _weights(d: np.ndarray, r, kernel: str) -> np.ndarray:
    """The kernel's weight of photons at distances d from the query, r the disc's radius."""
    if kernel == "uniform":
        return np.ones_like(d)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.clip(1.0 - d / r, 0.0, 1.0)
