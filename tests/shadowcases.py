"""One pixel's shadows on a light's plane for the windings' tests (tests only; imported by the
tests that use them, as strategies.py is; tests/ is on sys.path): a folded sheet of triangles
sharing corners, loose triangles, and triangles with corners on a coarse grid (touching,
collinear: often in doubt); and a whole scene whose crowded pixels the windings measure, a
noisy ball on a floor (`noisy_ball`)."""

from __future__ import annotations

import numpy as np


def sheet(rng, n: int, jitter: float) -> tuple[np.ndarray, np.ndarray]:
    """A grid of n x n corners jittered so that it folds over itself: (triangles (q, 3, 2),
    corner ids (q, 3))."""
    x, y = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float))
    pts = np.c_[x.ravel(), y.ravel()] + rng.normal(0, jitter, (n * n, 2))
    k = np.arange(n * n).reshape(n, n)[:-1, :-1].ravel()
    ids = np.r_[np.c_[k, k + 1, k + n + 1], np.c_[k, k + n + 1, k + n]]
    return pts[ids], ids


def loose(rng) -> tuple[np.ndarray, np.ndarray]:
    """1 to 29 triangles with corners of their own (ids from 100 on)."""
    q = int(rng.integers(1, 30))
    return rng.uniform(-2, 4, (q, 3, 2)), np.arange(3 * q).reshape(q, 3) + 100


def on_grid(rng) -> tuple[np.ndarray, np.ndarray]:
    """1 to 8 triangles of 12 ids at spots of a half-unit grid (some at one spot)."""
    spots = rng.integers(0, 5, (12, 2)) / 2.0
    ids = np.array([rng.choice(12, 3, replace=False) for _ in range(rng.integers(1, 9))])
    return spots[ids], ids


def no_area() -> tuple[np.ndarray, np.ndarray]:
    """Two triangles whose corners lie on one line (no area)."""
    tris, ids = np.zeros((2, 3, 2)), np.arange(6).reshape(2, 3)
    tris[:, :, 0] = [[0, 1, 2], [1, 2, 3]]
    return tris, ids


def free_but_one(rng, q: int, one: bool) -> np.ndarray:
    """(q,) bool: every shadow free (`pyramid.uncut`), or all but one at random with `one`."""
    free = np.ones(q, bool)
    if one:
        free[rng.integers(q)] = False
    return free


def noisy_ball(light):
    """A 20 x 20 scene: a noisy icosphere (trimesh's, 5,120 triangles, radii jittered by a
    seeded 8%) over a floor, under `light` (an AreaLight about (0, 2.5, 0) facing down)."""
    import trimesh

    from shadowvol.primitives import mesh, plane
    from shadowvol.scene import Camera, Material, Scene
    ico = trimesh.creation.icosphere(subdivisions=4, radius=0.5)
    rng = np.random.default_rng(0)
    v = ico.vertices * (1 + 0.08 * rng.standard_normal((len(ico.vertices), 1))) + [0.1, 1, -0.1]
    matte = Material(diffuse=[0.8, 0.8, 0.8])
    return Scene(camera=Camera(eye=[0, 4.5, 5.5], target=[0, 0, -0.5], fov_y=40.0),
                 objects=[plane("floor", size=[8, 8], material=matte),
                          mesh("blob", v, np.asarray(ico.faces), material=matte)],
                 lights=[light], width=20, height=20, ambient=[0, 0, 0])
