"""Small scenes, paths and named tolerances shared by the tests (the one builders module; tests
never import from each other).  Vary a built scene with `dataclasses.replace` /
`Scene.replace`.

The statistical checks of the path tracer and radiosity are z-tests on region means whose
variance the renderer itself estimates; `z_limit(tests)` gives the per-test bound that keeps the
false-alarm rate of a whole test function (all its regions and channels, Bonferroni) at
FALSE_ALARM."""

from __future__ import annotations

import math
import os
from pathlib import Path
from statistics import NormalDist

import numpy as np

from shadowvol.primitives import box, plane
from shadowvol.scene import Camera, DirectionalLight, Material, Scene
from shadowvol.scenefile import load_scene

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "scenes"
TEST_OUTPUT = ROOT / "test-output"
# the shared test meshes: ../shared/models beside the checkout, or where SHADOWVOL_MODELS says
# (a worktree elsewhere)
MODELS = Path(os.environ.get("SHADOWVOL_MODELS", ROOT.parent / "shared" / "models"))


def tiny_scene(with_blocker_behind_eye: bool = False) -> Scene:
    camera = Camera(eye=[0, 0, 5], target=[0, 0, 0], fov_y=math.degrees(2 * math.atan(0.2)))
    objects = [plane("backdrop", point=[0, 0, -5], normal=[0, 0, 1], size=[20, 20]),
               plane("A", point=[-1.45, 0, -4], normal=[0, 0, 1], size=[1.1, 4]),
               plane("B", point=[-2.45, 0, -3], normal=[0, 0, 1], size=[1.1, 4])]
    if with_blocker_behind_eye:
        # behind the camera, out of view, between the eye and the light: the eye is in its
        # shadow volume, no visible point is
        objects.append(plane("roof", point=[-3, 0, 8], normal=[0, 0, 1], size=[4, 10]))
    return Scene(camera=camera, objects=objects,
                 lights=[DirectionalLight(direction=[1, 0, -1])], width=4, height=4)


# ---- the path tracer and radiosity (the rendering equation's outlook) ----------------------

CORNELL = SCENES / "cornell.toml"

FALSE_ALARM = 1e-3  # probability that a correct renderer fails one statistical test function

# Depth-1 path tracing vs the masks' quadrature (raytrace.direct): the midpoint rule on 4^3
# points per emitter triangle misses or adds up to one point's share in deep penumbra; measured
# at most 0.32% of the image's median radiance on a 4x4 block at 48x48, allowed 1%.
QUADRATURE_ALLOWANCE = 0.01

# Path tracing vs radiosity, per object (area-averaged radiance), on top of z_limit standard
# errors of the path tracer: piecewise-constant patches at level 3 and Monte Carlo form factors
# (2048 rays a patch: the small light is hit by ~20 of a patch's rays) leave radiosity its own
# error, measured up to 5.0% over three seeds (short block), of which the path tracer's standard
# error (~0.9%) covers a part; allowed 4% on top of z_limit standard errors.
PT_RADIOSITY_RELATIVE = 0.04

# Radiosity furnace: shooting stops at unshot power <= tol of emitted; the radiance left unshot
# is bounded by tol / (1 - rho) of the answer.
RADIOSITY_TOL = 1e-6


BOX_CENTRE = np.array([278.0, 274.4, 279.6])  # the Cornell box's centre, mm


def facing_inside(obj, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """The normals (k, 3) of a Cornell object's points (k, 3) flipped to the face that the
    camera's side sees: walls face the box's centre, blocks face away from their own centre."""
    if "block" in obj.name:
        toward = points - obj.vertices.mean(axis=0)
    else:
        toward = BOX_CENTRE - points
    return normals * np.where((toward * normals).sum(axis=1) >= 0.0, 1.0, -1.0)[:, None]


def z_limit(tests: int, false_alarm: float = FALSE_ALARM) -> float:
    """|z| bound for each of `tests` two-sided tests so that any of them fails by chance with
    probability at most `false_alarm`."""
    return NormalDist().inv_cdf(1.0 - false_alarm / (2.0 * tests))


def cornell(size: int = 48) -> Scene:
    """The Cornell box scene file at size x size pixels."""
    return load_scene(CORNELL).replace(width=size, height=size)


def furnace(albedo, emission, size: int = 16) -> Scene:
    """A closed cube (side 2, centred at the origin) of one Lambertian material that reflects
    `albedo` and emits `emission` everywhere, seen from its centre: radiance E / (1 - rho)."""
    m = Material(diffuse=albedo, specular=[0, 0, 0], emission=emission)
    cam = Camera(eye=[0.0, 0.0, 0.0], target=[0.3, 0.2, -1.0], fov_y=90.0, near=0.01)
    return Scene(camera=cam, objects=[box("furnace", size=(2.0, 2.0, 2.0), material=m)],
                 lights=[], width=size, height=size, background=[0, 0, 0])


def block_means(image: np.ndarray, variance: np.ndarray, block: int):
    """Means of block x block pixel regions (H/b, W/b, 3) and the variance of each mean, for
    independent pixels with the given variances of their means."""
    H, W, _ = image.shape
    shape = (H // block, block, W // block, block, 3)
    mean = image.reshape(shape).mean(axis=(1, 3))
    var = variance.reshape(shape).sum(axis=(1, 3)) / block ** 4
    return mean, var


# Two square cards over a floor under a light straight down: each card's shadow is its own
# footprint.  A at height 1 covers x -1.0..0.2, z -0.6..0.6; B at height 0.5 covers
# x -0.2..1.0, z -0.3..0.9; on the floor the overlap x -0.2..0.2, z -0.3..0.6 has both bits,
# and on B the same region is A's.
CARDS = {"A": (1.0, (-1.0, 0.2), (-0.6, 0.6)), "B": (0.5, (-0.2, 1.0), (-0.3, 0.9))}
FLOOR = (0.0, (-4.0, 4.0), (-4.0, 4.0))


def cards_scene(width=160, height=120, light=None) -> Scene:
    def card(name, y, xs, zs, up=1.0):
        return plane(name, point=[sum(xs) / 2, y, sum(zs) / 2], normal=[0, up, 0],
                     size=[xs[1] - xs[0], zs[1] - zs[0]])
    # the floor is wound facing down, away from the camera: its normal must be turned up
    return Scene(camera=Camera(eye=[0.3, 4.0, 4.5], target=[0.0, 0.3, 0.0], fov_y=40.0),
                 objects=[card("floor", *FLOOR, up=-1.0), card("A", *CARDS["A"]),
                          card("B", *CARDS["B"])],
                 lights=[light or DirectionalLight([0.0, -1.0, 0.0])],
                 width=width, height=height)
