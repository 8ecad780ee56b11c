"""Small scenes, paths and named tolerances shared by the tests (the one builders module; tests
never import from each other).  Vary a built scene with `dataclasses.replace` /
`Scene.replace`.

The statistical checks of the path tracer and radiosity are z-tests on region means whose
variance the renderer itself estimates; `z_limit(tests)` gives the per-test bound that keeps the
false-alarm rate of a whole test function (all its regions and channels, Bonferroni) at
FALSE_ALARM.

Area lights: `square_over_floor` is the analytic case of the soft-shadow issue, a square
occluder parallel to a square light above a floor, seen from above; its exact answer is in
`square_visible_fraction`.  `check_counts` is the budget of raster against ray-traced
per-sample counts."""

from __future__ import annotations

import json
import math
import os
import shutil
from pathlib import Path
from statistics import NormalDist

import numpy as np
import pytest

from shadowvol.compare.maskdiff import count_edges, edge_pixels
from shadowvol.cameras import calibration, unproject
from shadowvol.primitives import box, plane, sphere
from shadowvol.scene import (
    AreaLight,
    Camera,
    DirectionalLight,
    Material,
    Object,
    PointLight,
    Scene,
    SpotLight,
)
from shadowvol.scenefile import load_scene

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "scenes"
TEST_OUTPUT = ROOT / "test-output"
# the shared test meshes: ../shared/models beside the checkout, or where SHADOWVOL_MODELS says
# (a worktree elsewhere)
# Set by .ci/run, which installs the system packages: then a missing one fails instead of
# skipping, so CI runs every test that needs one.
REQUIRE_SYSTEM = "SHADOWVOL_REQUIRE_SYSTEM"


def system_program(names: tuple[str, ...], package: str) -> str:
    """The path of the first of `names` on PATH, a program that pip cannot install (a real
    browser, an X server).  Missing: the test skips, naming the Debian package to install;
    under $SHADOWVOL_REQUIRE_SYSTEM=1 (CI) it fails."""
    for name in names:
        path = shutil.which(name)
        if path:
            return path
    why = (f"needs {names[0]}, a system program pip cannot install: apt-get install {package} "
           f"(.ci/run does)")
    if os.environ.get(REQUIRE_SYSTEM) == "1":
        pytest.fail(f"{why}; ${REQUIRE_SYSTEM}=1 says it must be there")
    pytest.skip(why)


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

# Depth-1 path tracing vs the masks' quadrature (raytrace.outlook.direct): the midpoint rule on 4^3
# points per emitter triangle misses or adds up to one point's share in deep penumbra; measured
# at most 0.32% of the image's median radiance on a 4x4 block at 48x48, allowed 1%.
QUADRATURE_ALLOWANCE = 0.01

# Path tracing vs radiosity at radiosity's defaults, per object (area-averaged radiance, the
# path tracer's standard error held below a quarter of this): measured within 0.8% over three
# seeds (benchmarks/bench_radiosity.py, docs/course.md); the bound, 2%.
PT_RADIOSITY_RELATIVE = 0.02

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


# ---- area lights (soft shadows) ------------------------------------------------------------

FLOOR_Y, OCCLUDER_Y, LIGHT_Y = 0.0, 1.0, 2.5
LIGHT_SIDE, OCCLUDER_SIDE, FLOOR_HALF = 1.2, 1.0, 4.0
OCCLUDER_CENTER = np.array([0.15, OCCLUDER_Y, -0.1])
# Raster against ray tracer counts: pixels whose counts may differ, at most, as a fraction of
# all pixels (and only on edges of the samples' hard masks or of the coverage): the hard masks'
# budget (conftest.MAX_MISMATCH_FRACTION), per light however many samples it has.
MAX_DIFFERING_FRACTION = 0.001
# A cell whose covered fraction is within this of 0 or 1 counts as uncovered or covered (the
# overlaps are differences of float64 coordinates of ~1).
COVER_ROUNDING = 1e-9
MATTE = Material(ambient=[0.0, 0.0, 0.0], diffuse=[0.8, 0.8, 0.8], specular=[0.0, 0.0, 0.0])


def square_light(samples: int, pattern: str = "stratified", seed: int = 0, **kw) -> AreaLight:
    return AreaLight("rect", [0.0, LIGHT_Y, 0.0], normal=[0.0, -1.0, 0.0],
                     size=[LIGHT_SIDE, LIGHT_SIDE], samples=samples, pattern=pattern, seed=seed,
                     **kw)


def square_over_floor(light, size: int = 64) -> Scene:
    """Floor (y = 0, 8 x 8), a square occluder (y = 1) and `light`, camera above and in front."""
    floor = plane("floor", point=[0.0, FLOOR_Y, 0.0], size=[2 * FLOOR_HALF, 2 * FLOOR_HALF],
                  material=MATTE)
    occluder = plane("occluder", point=OCCLUDER_CENTER, size=[OCCLUDER_SIDE, OCCLUDER_SIDE],
                     material=MATTE)
    camera = Camera(eye=[0.0, 4.5, 5.5], target=[0.0, 0.0, -0.5], fov_y=40.0)
    return Scene(camera=camera, objects=[floor, occluder], lights=[light], width=size,
                 height=size, ambient=[0.0, 0.0, 0.0])


def floor_points(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """Each pixel's pixel-centre ray cut with the floor plane: points (H, W, 3) float64, and
    `on_floor` (H, W) bool, the pixels where that ray meets the floor, and not the occluder
    first."""
    from raytrace.camera import primary_rays

    o, d = primary_rays(scene.camera, scene.width, scene.height)
    p = o + ((FLOOR_Y - o[:, 1]) / d[:, 1])[:, None] * d
    q = o + ((OCCLUDER_Y - o[:, 1]) / d[:, 1])[:, None] * d
    half = OCCLUDER_SIDE / 2
    hides = (np.abs(q[:, 0] - OCCLUDER_CENTER[0]) <= half) & \
        (np.abs(q[:, 2] - OCCLUDER_CENTER[2]) <= half)
    on_floor = (d[:, 1] < 0) & (np.abs(p[:, 0]) < FLOOR_HALF) & (np.abs(p[:, 2]) < FLOOR_HALF)
    shape = (scene.height, scene.width)
    return p.reshape(shape + (3,)), (on_floor & ~hides).reshape(shape)


def _overlap(lo: np.ndarray, hi: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Length of [lo, hi] ∩ [a, b], elementwise."""
    return np.clip(np.minimum(hi, b) - np.maximum(lo, a), 0.0, None)


def _shadow_interval(p: np.ndarray, axis: int) -> tuple[np.ndarray, np.ndarray]:
    """The occluder's extent along `axis` projected from floor points p (..., 3) onto the
    light's plane (a central projection from p, factor k = light height / occluder height)."""
    k = (LIGHT_Y - FLOOR_Y) / (OCCLUDER_Y - FLOOR_Y)
    half = OCCLUDER_SIDE / 2
    c = OCCLUDER_CENTER[axis]
    x = p[..., axis]
    return x + k * (c - half - x), x + k * (c + half - x)


def square_visible_fraction(p: np.ndarray) -> np.ndarray:
    """(...,) float64: the exact fraction of the square light visible from floor points p:
    1 - (product of the two 1D overlaps of the occluder's shadow with the light) / area."""
    half = LIGHT_SIDE / 2
    blocked = np.ones(p.shape[:-1])
    for axis in (0, 2):
        lo, hi = _shadow_interval(p, axis)
        blocked = blocked * _overlap(lo, hi, -half, half) / LIGHT_SIDE
    return 1.0 - blocked


def stratified_bound(p: np.ndarray, n: int) -> np.ndarray:
    """(...,) float64: the error bound of an n x n stratified estimate of the visible fraction
    at p: the cells the shadow covers only in part, / n².  A cell covered wholly (or not at
    all) holds its sample inside (outside) the shadow, so only these cells can be wrong, each
    by less than 1/n²."""
    half = LIGHT_SIDE / 2
    edges = -half + LIGHT_SIDE * np.arange(n + 1) / n
    fractions = []
    for axis in (0, 2):
        lo, hi = _shadow_interval(p, axis)
        fractions.append(_overlap(lo[..., None], hi[..., None], edges[:-1], edges[1:])
                         * n / LIGHT_SIDE)  # (..., n) covered fraction of each column
    cover = fractions[0][..., :, None] * fractions[1][..., None, :]
    partial = (cover > COVER_ROUNDING) & (cover < 1 - COVER_ROUNDING)
    return partial.sum(axis=(-1, -2)) / n**2


def blocked_samples(p: np.ndarray, samples: np.ndarray) -> np.ndarray:
    """(..., N) bool: the segment from floor point p (..., 3) to each sample (N, 3) of the
    light crosses the occluder's square (computed analytically, float64), and the distance
    (..., N) of that crossing from the square's outline (how close the call is)."""
    t = (OCCLUDER_Y - p[..., None, 1]) / (samples[:, 1] - p[..., None, 1])
    if np.any(t >= 1):
        raise ValueError("every sample must lie above the occluder")
    q = p[..., None, :] + t[..., None] * (samples - p[..., None, :])
    half = OCCLUDER_SIDE / 2
    dx = half - np.abs(q[..., 0] - OCCLUDER_CENTER[0])
    dz = half - np.abs(q[..., 2] - OCCLUDER_CENTER[2])
    inside = (dx > 0) & (dz > 0)
    margin = np.where(inside, np.minimum(dx, dz),
                      np.hypot(np.minimum(dx, 0), np.minimum(dz, 0)))
    return inside, margin


def _sample_edges(scene, i: int) -> np.ndarray:
    """(H, W) bool: pixels on an edge of some sample's reference hard mask of light i."""
    from raytrace.soft import sample_masks

    edges = np.zeros((scene.height, scene.width), bool)
    for _, lit in sample_masks(scene, i):
        for mask in lit:
            edges |= edge_pixels(mask)
    return edges


def check_counts(scene, got, ref) -> list[dict]:
    """Raster `got` (RenderResult) against ray tracer `ref` (SoftMasks): per light the
    pixels whose counts differ, in total and off every sample edge (must be 0), the largest
    difference.  Sample edges are those of the ray tracer's hard masks and those the raster's
    count shows (`count_edges`), as `maskdiff` takes the edges of either renderer's masks.
    Fails the test beyond the budget."""
    near_cov = edge_pixels(got.coverage) | edge_pixels(ref.coverage)
    rows = []
    for i in range(len(scene.lights)):
        differ = got.lit_count[i] != ref.lit_count[i]
        edges = _sample_edges(scene, i) | count_edges(got.lit_count[i])
        interior = differ & ~(near_cov | edges)
        rows.append({"light": i, "samples": int(ref.samples[i]), "differ": int(differ.sum()),
                     "interior": int(interior.sum()),
                     "largest": int(np.abs(got.lit_count[i].astype(int)
                                           - ref.lit_count[i]).max())})
    pixels = scene.width * scene.height
    assert all(r["interior"] == 0 for r in rows), rows
    assert all(r["differ"] <= MAX_DIFFERING_FRACTION * pixels for r in rows), rows
    np.testing.assert_array_equal(got.lit, got.lit_count == ref.samples[:, None, None])
    return rows


def check_facing_counts(scene, got, ref) -> list[dict]:
    """Raster `got` against ray tracer `ref` (frames with facing_count): per light the pixels
    whose facing counts differ must all lie on an edge (one pixel) of some sample's facing
    mask (the ray tracer's), of the raster's count or of either coverage, and be few (as
    `check_counts`).  Fails the test beyond the budget."""
    from raytrace.soft import sample_masks

    near_cov = edge_pixels(got.coverage) | edge_pixels(ref.coverage)
    rows = []
    for i in range(len(scene.lights)):
        edges = count_edges(got.facing_count[i]) | near_cov
        for _, facing in sample_masks(scene, i, facing=True):
            for mask in facing:
                edges |= edge_pixels(mask)
        differ = got.facing_count[i] != ref.facing_count[i]
        rows.append({"light": i, "differ": int(differ.sum()),
                     "interior": int((differ & ~edges).sum())})
    pixels = scene.width * scene.height
    assert all(r["interior"] == 0 for r in rows), rows
    assert all(r["differ"] <= MAX_DIFFERING_FRACTION * pixels for r in rows), rows
    np.testing.assert_array_equal(got.facing, got.facing_count > 0)
    return rows


# ---- batch jobs (tests/batch) ----------------------------------------------------------

def job_lines(frames: int = 4, size=(40, 30), raytrace: bool = True) -> list[dict]:
    """A turntable of the cage scene (rasterized) and, optionally, two ray-traced frames of it
    with a light override and jitter: every kind of job field the runs must agree on."""
    jobs = [{"name": "cage-turntable", "scene": str(SCENES / "cage.toml"), "size": list(size),
             "cameras": {"orbit": {"center": [-0.6, 1.0, -0.8], "radius": 7.0,
                                   "elevation": 30.0, "start": 20.0, "sweep": 60.0,
                                   "frames": frames}},
             "outputs": ["image", "masks"]}]
    if raytrace:
        jobs.append({"name": "cage-traced", "scene": str(SCENES / "cage.toml"),
                     "size": [24, 18], "renderer": "raytrace", "max_depth": 1, "seed": 7,
                     "jitter": {"eye": 0.2, "lights": 0.1},
                     "lights": [{"type": "point", "position": [0.0, 1.4, 0.0]},
                                {"type": "directional", "direction": [-0.3, -1.0, -0.4],
                                 "intensity": 0.5}],
                     "cameras": [{"eye": [4.2, 3.4, 5.2], "target": [-0.6, 1.0, -0.8]},
                                 {"eye": [3.0, 2.0, 6.0], "target": [-0.6, 1.0, -0.8],
                                  "fov_y": 40.0}]})
    return jobs


def write_jobs(path: Path, jobs: list, extra_lines: tuple[str, ...] = ()) -> Path:
    path.write_text("".join(json.dumps(j) + "\n" for j in jobs) +
                    "".join(line + "\n" for line in extra_lines))
    return path


def output_files(out: Path) -> dict[str, bytes]:
    """Every file under `out` but the manifests, by relative path, with its bytes."""
    return {p.relative_to(out).as_posix(): p.read_bytes() for p in sorted(out.rglob("*"))
            if p.is_file() and not p.name.startswith("manifest")}


def manifest_hashes(out: Path, name: str = "manifest.jsonl") -> list[tuple]:
    """(id, output, sha256) of every file the manifest lists, and each record's error, in
    manifest order: what must not depend on how the frames were made."""
    rows = []
    for line in (out / name).read_text().splitlines():
        record = json.loads(line)
        if "files" in record:
            rows += [(record["id"], k, v["sha256"]) for k, v in record["files"].items()]
        elif "tar" in record:
            rows.append((record["id"], "tar", record["sha256"]))
        else:
            rows.append((record["id"], "error", record["error"]))
    return rows


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


def mixed_scene(seed: int, lights: int = 3) -> Scene:
    """A floor, closed spheres and boxes (cullable, `methods.cullable`), `lights` lights of every
    kind above them in turn (point, directional, spot), 96 x 72: the deferred frame's and the
    mask pass's tests."""
    rng = np.random.default_rng(seed)
    objects = [plane("floor", size=[12, 12])]
    for i in range(4):
        c = [rng.uniform(-3, 3), rng.uniform(0.5, 2.0), rng.uniform(-3, 2)]
        m = Material(diffuse=rng.uniform(0.2, 0.9, 3), specular=[0.3] * 3, shininess=20)
        objects.append(sphere(f"s{i}", c, rng.uniform(0.3, 0.8), m, subdivisions=2) if i % 2
                       else box(f"b{i}", c, rng.uniform(0.3, 1.2, 3), m))
    kinds = [lambda: PointLight([rng.uniform(-4, 4), rng.uniform(5, 8), rng.uniform(-2, 4)],
                                intensity=0.3),
             lambda: DirectionalLight([rng.uniform(-0.5, 0.5), -1, rng.uniform(-0.5, 0.5)],
                                      intensity=0.3),
             lambda: SpotLight([rng.uniform(-2, 2), 6, 2], [0, -1, -0.3], cone_angle=50,
                               intensity=0.3)]
    return Scene(camera=Camera(eye=[0, 4, 9], target=[0, 0.8, 0]), objects=objects,
                 lights=[kinds[i % 3]() for i in range(lights)], width=96, height=72)


# ---- shadow switches (docs/CONVENTIONS.md, "Shadow switches") ---------------------------

def overlapping_shadows(width: int = 80, height: int = 60) -> Scene:
    """A floor (object 0), a post (1), a ball (2) and a card (3) above them whose shadows
    overlap on the floor and on each other, under a point, a directional, a spot and a rect
    area light of 4 samples."""
    objects = [plane("floor", size=[8, 8]), box("post", [0.0, 0.75, 0.0], [0.5, 1.5, 0.5]),
               sphere("ball", [0.7, 0.55, 0.5], 0.45, subdivisions=2),
               plane("card", point=[0.3, 2.2, 0.3], size=[1.0, 1.0])]
    lights = [PointLight([1.5, 4.0, 1.5], intensity=0.4),
              DirectionalLight([-0.3, -1.0, -0.2], intensity=0.4),
              SpotLight([-1.0, 4.0, 1.0], [0.2, -1.0, -0.2], cone_angle=40, intensity=0.4),
              AreaLight("rect", [0.5, 4.0, 0.5], normal=[0.0, -1.0, 0.0], size=[1.0, 1.0],
                        samples=4, intensity=0.4)]
    return Scene(camera=Camera(eye=[0.5, 4.0, 5.0], target=[0.2, 0.6, 0.0], fov_y=45.0),
                 objects=objects, lights=lights, width=width, height=height)


def switched(scene: Scene, cast=(), receive=(), lights=()) -> Scene:
    """`scene` with `cast_shadows` off for the objects `cast`, `receive_shadows` off for the
    objects `receive` and `shadows` off for the lights `lights` (indices)."""
    import dataclasses

    objects = [dataclasses.replace(o, **({"cast_shadows": False} if k in cast else {}),
                                   **({"receive_shadows": False} if k in receive else {}))
               if k in cast or k in receive else o for k, o in enumerate(scene.objects)]
    return scene.replace(objects=objects, lights=[
        dataclasses.replace(lt, shadows=False) if k in lights else lt
        for k, lt in enumerate(scene.lights)])


def check_cast_switch(before, after, j: int, objects: int) -> np.ndarray:
    """One renderer's frames (lit, lit_count, facing_count, casters, object_id, coverage)
    before and after object j's `cast_shadows` is turned off: every bit of casters but j's
    unchanged and j's cleared; where j alone shadowed a pixel (no other bit) it is lit by
    every facing sample, where j's bit was not set nothing changed, elsewhere the count only
    rose; the rest unchanged.  Returns `alone` (L, H, W) bool."""
    from shadowvol.frame import decode_casters

    bits = decode_casters(before.casters, objects)
    others = np.delete(bits, j, axis=-1).any(-1)
    alone = bits[..., j] & ~others
    want = bits.copy()
    want[..., j] = False
    np.testing.assert_array_equal(decode_casters(after.casters, objects), want)
    changed = after.lit_count != before.lit_count
    assert not (changed & ~bits[..., j]).any(), "a count changed where j cast nothing"
    np.testing.assert_array_equal(after.lit_count[alone], before.facing_count[alone])
    assert (after.lit_count >= before.lit_count).all()
    hard = before.samples == 1
    np.testing.assert_array_equal(after.lit[hard], before.lit[hard] | alone[hard])
    for name in ("coverage", "facing_count", "object_id"):
        np.testing.assert_array_equal(getattr(after, name), getattr(before, name))
    # the scene tests something: j alone, and j with another caster
    assert alone.any() and (bits[..., j] & others).any()
    return alone


def check_receive_switch(before, after, k: int) -> np.ndarray:
    """The same for object k's `receive_shadows` off: on k's pixels every light's count is
    its facing count and no caster is named; everywhere else nothing changed.  Returns k's
    pixels (H, W) bool."""
    own = before.object_id == k + 1
    np.testing.assert_array_equal(after.lit_count[:, own], before.facing_count[:, own])
    assert not after.casters[:, own].any()
    np.testing.assert_array_equal(after.lit_count[:, ~own], before.lit_count[:, ~own])
    np.testing.assert_array_equal(after.casters[:, ~own], before.casters[:, ~own])
    for name in ("coverage", "facing_count", "object_id"):
        np.testing.assert_array_equal(getattr(after, name), getattr(before, name))
    assert (before.lit_count[:, own] < before.facing_count[:, own]).any()   # k had shadow
    return own


def check_light_switch(before, after, i: int) -> None:
    """The same for light i's `shadows` off: its lit is its own facing output (coverage ∧
    n·l > 0 toward some sample, inside the cone) for every sample (lit_count ==
    facing_count), no caster is named for it; every other light unchanged."""
    np.testing.assert_array_equal(after.lit_count[i], before.facing_count[i])
    np.testing.assert_array_equal(after.lit[i], before.facing_count[i] == before.samples[i])
    if before.samples[i] == 1:
        np.testing.assert_array_equal(after.lit[i], before.facing[i] & before.coverage)
    assert not after.casters[i].any()
    others = [m for m in range(len(before.lit)) if m != i]
    for name in ("lit", "lit_count", "casters"):
        np.testing.assert_array_equal(getattr(after, name)[others],
                                      getattr(before, name)[others])
    assert (before.lit_count[i] < before.facing_count[i]).any()   # it had shadow


def camera_from_matrices(K, camera_to_world, near: float = 0.05) -> Camera:
    """The camera a dataset user reads back from a frame's K (3, 3) and camera_to_world
    (4, 4) (docs/CONVENTIONS.md, "Camera matrices"); `near` is not in them."""
    return Camera(fx=K[0, 0], fy=K[1, 1], cx=K[0, 2], cy=K[1, 2],
                  camera_to_world=camera_to_world, near=near)


def off_centre(scene: Scene, aspect: float = 1.3, shift=(0.21, -0.16)) -> Scene:
    """`scene` seen through non-square pixels and an off-centre principal point: its look-at
    camera's pose, fx = `aspect` * fy (fy its focal length in pixels), and the principal
    point moved from the image centre by `shift` (fractions of the width and the height)."""
    cal = calibration(scene)
    f = cal.K[1, 1]
    camera = Camera(fx=aspect * f, fy=f, cx=scene.width * (0.5 + shift[0]),
                    cy=scene.height * (0.5 + shift[1]), camera_to_world=cal.camera_to_world,
                    near=scene.camera.near)
    return scene.replace(camera=camera)


# Cameras by matrices (`pixel_targets`): fronto-parallel squares of this half-size in pixels,
# centred within MISS pixels of a pixel centre: a camera off by more than HALF - MISS = 0.2 px
# (OpenCV's whole-number centres are 0.5 px off) misses the square at that pixel
HALF, MISS = 0.3, 0.1
# depth is the pixel's ray met with the triangle's float32 plane (CONVENTIONS, "depth")
DEPTH_RTOL = 1e-6


def rotation(axis, degrees: float) -> np.ndarray:
    """(3, 3) float64 rotation about `axis` (Rodrigues)."""
    k = np.asarray(axis, np.float64) / np.linalg.norm(axis)
    a = np.radians(degrees)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(a) * kx + (1 - np.cos(a)) * kx @ kx


def project(K: np.ndarray, camera_to_world: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(n, 3) world points -> (n, 3) float64 (u, v, depth), plainly from the definitions: the
    OpenGL camera coordinates by solving with camera_to_world, flipped to OpenCV's, times K."""
    gl = np.linalg.solve(camera_to_world, np.c_[points, np.ones(len(points))].T).T[:, :3]
    cv = gl * [1.0, -1.0, -1.0]
    uvw = cv @ K.T
    return np.c_[uvw[:, :2] / uvw[:, 2:], cv[:, 2]]


def pixel_targets(seed: int, width: int = 64, height: int = 48, n: int = 8):
    """A scene of `n` small squares facing a turned camera with fx != fy and an off-centre
    principal point, each square centred near the centre of a known pixel, and the squares'
    centres (n, 3), the pixels (n, 2) (x, y) and the camera's K."""
    rng = np.random.default_rng(seed)
    m = np.eye(4)
    m[:3, :3] = rotation(rng.normal(size=3), rng.uniform(20, 160))
    m[:3, 3] = rng.uniform(-5, 5, 3)
    fx, fy = rng.uniform(50, 90), rng.uniform(50, 90)
    cx, cy = width * rng.uniform(0.2, 0.8), height * rng.uniform(0.2, 0.8)
    camera = Camera(fx=fx, fy=fy, cx=cx, cy=cy, camera_to_world=m)
    K = np.array([[fx, 0, cx], [0, fy, cy], [0, 0, 1.0]])
    pixels = np.stack([rng.choice(np.arange(2, width - 2), n, replace=False),
                       rng.choice(np.arange(2, height - 2), n, replace=False)], axis=1)
    uv = pixels + 0.5 + rng.uniform(-MISS, MISS, (n, 2))
    z = rng.uniform(2.0, 9.0, n)
    right, up = m[:3, 0], m[:3, 1]
    objects, centres = [], []
    for k in range(n):
        gl = np.array([(uv[k, 0] - cx) / fx * z[k], -(uv[k, 1] - cy) / fy * z[k], -z[k], 1.0])
        c = (m @ gl)[:3]
        hx, hy = HALF * z[k] / fx * right, HALF * z[k] / fy * up
        corners = [c - hx - hy, c + hx - hy, c + hx + hy, c - hx + hy]
        objects.append(Object(f"square{k}", corners, [[0, 1, 2], [0, 2, 3]]))
        centres.append(c)
    scene = Scene(camera=camera, objects=objects, lights=[DirectionalLight(-m[:3, 2])],
                  width=width, height=height)
    return scene, np.array(centres), pixels, K


def check_seen(K, camera_to_world, centres, pixels, object_id, depth, normal) -> None:
    """Each square k is seen at its pixel, at its depth, with its normal; unprojected, the
    pixel gives back a point of the square (within its half-size)."""
    uvz = project(K, camera_to_world, centres)
    np.testing.assert_array_equal(np.floor(uvz[:, :2]).astype(int), pixels)
    xs, ys = pixels[:, 0], pixels[:, 1]
    assert object_id[ys, xs].tolist() == list(range(1, len(pixels) + 1))
    np.testing.assert_allclose(depth[ys, xs], uvz[:, 2], rtol=DEPTH_RTOL)
    back = camera_to_world[:3, 2]
    np.testing.assert_allclose(np.abs(normal[ys, xs] @ back), 1.0, rtol=1e-6)
    points = unproject(K, camera_to_world, depth)[ys, xs]
    pixel_size = uvz[:, 2] / min(K[0, 0], K[1, 1])
    assert (np.linalg.norm(points - centres, axis=1) <= (HALF + MISS) * 1.5 * pixel_size).all()
    # and nothing else: a square is 0.6 px wide, so it covers at most 4 pixels
    assert 0 < (object_id > 0).sum() <= 4 * len(pixels)


# ---------------------------------------------------------------------------------------------
# Textured meshes, written by hand (the files the loaders read, made in the tests themselves)
# ---------------------------------------------------------------------------------------------

# The raster-vs-ray image budget of `test_soft_raster.test_image_is_the_ray_tracers_direct_light`:
# a channel more than IMAGE_TOL apart in at most IMAGE_BUDGET of the pixels (float32 against
# float64 shading of the same point)
IMAGE_TOL, IMAGE_BUDGET = 1e-4, 0.002
# a quad on the ground (y = 0), its UVs (glTF's convention) reaching past [0, 1] so that the
# wrap modes show, and the GL enums of glTF's samplers
QUAD = np.array([[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]], np.float32)
QUAD_UV = np.array([[-0.3, -0.2], [1.37, -0.2], [1.37, 1.61], [-0.3, 1.61]], np.float32)
GL_NEAREST, GL_LINEAR, GL_REPEAT, GL_CLAMP, GL_MIRROR = 9728, 9729, 10497, 33071, 33648


def png_bytes(texels: np.ndarray) -> bytes:
    import io

    from PIL import Image

    buffer = io.BytesIO()
    Image.fromarray(texels).save(buffer, format="PNG")
    return buffer.getvalue()


def textured_glb(path: Path, texels: np.ndarray, *, wrap=GL_REPEAT, filt=GL_NEAREST,
                 factor=(1.0, 1.0, 1.0, 1.0), material: dict | None = None,
                 image_uri: str | None = None, vertices=QUAD, uv=QUAD_UV,
                 colours=None) -> Path:
    """A GLB of one quad (two triangles) with a baseColorTexture of `texels` (h, w, 3) uint8
    (in the file, or at `image_uri` beside it), its sampler's wrap (both axes) and filter,
    `factor` the baseColorFactor, `material` more keys of the material, `colours` (4, 3)
    float32 its COLOR_0."""
    chunks, views = [], []

    def view(data: bytes) -> int:
        views.append({"buffer": 0, "byteOffset": sum(len(c) for c in chunks),
                      "byteLength": len(data)})
        chunks.append(data + b"\0" * (-len(data) % 4))
        return len(views) - 1

    indices = np.array([0, 1, 2, 0, 2, 3], np.uint16)
    accessors = [
        {"bufferView": view(np.asarray(vertices, np.float32).tobytes()), "componentType": 5126,
         "count": 4, "type": "VEC3", "min": np.min(vertices, 0).tolist(),
         "max": np.max(vertices, 0).tolist()},
        {"bufferView": view(np.asarray(uv, np.float32).tobytes()), "componentType": 5126,
         "count": 4, "type": "VEC2"},
        {"bufferView": view(indices.tobytes()), "componentType": 5123, "count": 6,
         "type": "SCALAR"}]
    attributes = {"POSITION": 0, "TEXCOORD_0": 1}
    if colours is not None:
        attributes["COLOR_0"] = len(accessors)
        accessors.append({"bufferView": view(np.asarray(colours, np.float32).tobytes()),
                          "componentType": 5126, "count": 4, "type": "VEC3"})
    image = {"uri": image_uri} if image_uri else \
        {"bufferView": view(png_bytes(texels)), "mimeType": "image/png"}
    if image_uri and texels is not None:
        (path.parent / image_uri).write_bytes(png_bytes(texels))
    document = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "quad", "mesh": 0}],
        "meshes": [{"name": "quad", "primitives": [{
            "attributes": attributes, "indices": 2, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                                "baseColorFactor": list(factor)},
                       **(material or {})}],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": filt, "minFilter": filt, "wrapS": wrap, "wrapT": wrap}],
        "images": [image], "accessors": accessors, "bufferViews": views,
        "buffers": [{"byteLength": sum(len(c) for c in chunks)}]}
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    binary = b"".join(chunks)
    body = (len(text).to_bytes(4, "little") + b"JSON" + text
            + len(binary).to_bytes(4, "little") + b"BIN\0" + binary)
    path.write_bytes(b"glTF" + (2).to_bytes(4, "little")
                     + (12 + len(body)).to_bytes(4, "little") + body)
    return path


def textured_scene_file(folder: Path, mesh: str, width: int = 96, height: int = 80) -> Path:
    """A scene file in `folder` of the mesh file `mesh` (a name in `folder`) seen from above
    at an angle, lit by one point light."""
    path = folder / "textured.toml"
    path.write_text(f'''[image]
width = {width}
height = {height}
[camera]
eye = [0.3, 2.2, 1.9]
target = [0.0, 0.0, 0.0]
fov_y = 50
[[lights]]
type = "point"
position = [0.5, 3.0, 1.0]
intensity = 0.9
[[objects]]
type = "mesh"
path = "{mesh}"
''')
    return path


def pose_scenes(folder: Path) -> tuple[Path, Path]:
    """Two scene files sharing classes and a mesh file (an asymmetric crate, `crate.obj`):
    A: floor, two crates (a matrix and an Euler transform), a ball (category "ball");
    B: floor, the same ball, a box of category "crate" (another model of that class), a crate
    tilted by a matrix.  Planes are the background."""
    corners = np.array([[x, y, z] for x in (-0.3, 0.3) for y in (-0.17, 0.17)
                        for z in (-0.12, 0.12)])
    corners[7] += [0.2, 0.05, 0.0]   # no symmetry: a wrong turn shows
    faces = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
             [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    (folder / "crate.obj").write_text(
        "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in corners.tolist()) +
        "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces))
    turn = rotation([0, 1, 0], 35.0)
    tilt = rotation([1, 0, 0], 25.0) @ rotation([0, 0, 1], 15.0)
    matrix_a = [[*turn[i], [-0.8, 0.2, 0.0][i]] for i in range(3)] + [[0, 0, 0, 1]]
    matrix_b = [[*tilt[i], [-0.7, 0.45, 0.2][i]] for i in range(3)] + [[0, 0, 0, 1]]
    head = ('[camera]\neye = [0.0, 2.2, 4.5]\ntarget = [0.0, 0.3, 0.0]\nfov_y = 45.0\n\n'
            '[[lights]]\ntype = "point"\nposition = [1.5, 3.0, 1.5]\n\n'
            '[[objects]]\nname = "floor"\ntype = "plane"\nsize = [6.0, 6.0]\n\n')
    ball = ('[[objects]]\nname = "ball"\ntype = "sphere"\ncenter = [0.0, 0.3, -0.6]\n'
            'radius = 0.3\nsubdivisions = 2\ncategory = "ball"\n\n')
    a = (head + '[[objects]]\nname = "crate left"\ntype = "mesh"\npath = "crate.obj"\n'
         f'transform = {{ matrix = {json.dumps(matrix_a)} }}\n\n'
         '[[objects]]\nname = "crate right"\ntype = "mesh"\npath = "crate.obj"\n'
         'transform = { rotation = [0.0, -60.0, 0.0], translation = [0.7, 0.2, 0.3] }\n\n'
         + ball)
    b = (head + ball + '[[objects]]\nname = "box"\ntype = "box"\ncenter = [0.8, 0.25, 0.0]\n'
         'size = [0.4, 0.5, 0.4]\ncategory = "crate"\n\n'
         '[[objects]]\nname = "tilted crate"\ntype = "mesh"\npath = "crate.obj"\n'
         f'transform = {{ matrix = {json.dumps(matrix_b)} }}\n')
    (folder / "poses_a.toml").write_text(a)
    (folder / "poses_b.toml").write_text(b)
    return folder / "poses_a.toml", folder / "poses_b.toml"


def pose_jobs(folder: Path) -> list[dict]:
    """Two jobs of `pose_scenes`: A rasterized, B ray traced with its objects jittered."""
    a, b = pose_scenes(folder)
    return [{"name": "crates", "scene": str(a), "size": [64, 48], "outputs": ["image"],
             "cameras": {"orbit": {"center": [0.0, 0.3, 0.0], "radius": 4.5,
                                   "elevation": 25.0, "sweep": 50.0, "frames": 2}}},
            {"name": "tossed", "scene": str(b), "size": [64, 48], "renderer": "raytrace",
             "max_depth": 1, "seed": 3, "outputs": ["image"],
             "jitter": {"objects": {"translation": 0.15, "rotation": 40.0}},
             "cameras": [{"eye": [0.5, 2.4, 4.2], "target": [0.0, 0.3, 0.0]},
                         {"eye": [-1.5, 2.0, 4.0], "target": [0.0, 0.3, 0.0]}]}]
