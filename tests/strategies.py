"""Hypothesis strategies for random scenes, and the test profiles (imported by the robustness
tests; tests/ is on sys.path because it has a conftest.py and no __init__.py).

Profiles, chosen by the environment variable HYPOTHESIS_PROFILE:

* `ci` (the default): a few dozen scenes, derandomized (the same scenes on every run), so that
  CI is reproducible and bounded (well under a minute);
* `long`: hundreds of scenes, also derandomized (with its own, larger, deterministic set), for a
  run by hand:  HYPOTHESIS_PROFILE=long pytest tests/test_robustness_property.py -s

Coordinates are drawn from a grid of sixteenths: exact in float32 and float64, which makes exact
coplanarity, collinearity, duplicated vertices and lights in a triangle's plane common instead
of practically impossible, and keeps shrunk examples readable.
"""

from __future__ import annotations

import dataclasses
import os

import numpy as np
from hypothesis import HealthCheck, assume, settings
from hypothesis import strategies as st

from shadowvol.primitives import Transform, box, mesh, plane, sphere
from shadowvol.scene import (
    Camera,
    DirectionalLight,
    Material,
    PointLight,
    Scene,
    SceneError,
    SpotLight,
)

settings.register_profile(
    "ci", max_examples=50, derandomize=True, deadline=None, print_blob=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow,
                           HealthCheck.filter_too_much])
settings.register_profile(
    "long", max_examples=1500, derandomize=True, deadline=None, print_blob=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow,
                           HealthCheck.filter_too_much])
PROFILE = os.environ.get("HYPOTHESIS_PROFILE", "ci")
if PROFILE not in ("ci", "long"):
    raise RuntimeError(f"HYPOTHESIS_PROFILE must be 'ci' or 'long', got {PROFILE!r}")


def profile() -> settings:
    """The settings of the profile chosen by HYPOTHESIS_PROFILE (default `ci`)."""
    return settings.get_profile(PROFILE)


RED = Material(ambient=[0.4, 0.1, 0.1], diffuse=[0.8, 0.2, 0.2])
GREY = Material(ambient=[0.5, 0.5, 0.45], diffuse=[0.8, 0.8, 0.7], specular=[0, 0, 0])


def coord(low: float = -3.0, high: float = 3.0):
    """A number on the grid of sixteenths in [low, high]."""
    return st.integers(int(low * 16), int(high * 16)).map(lambda k: k / 16)


def point(low=-3.0, high=3.0):
    return st.tuples(coord(low, high), coord(low, high), coord(low, high)).map(list)


def direction():
    return point(-1.0, 1.0).filter(lambda v: any(v))


@st.composite
def soup(draw, name: str):
    """An open or non-manifold triangle soup: a few grid points, triangles on them (shared
    vertices and edges, an edge on three triangles, duplicates), whatever winding."""
    n = draw(st.integers(3, 7))
    centre = np.array(draw(point(-2.0, 2.0)))
    pts = centre + np.array([draw(point(-1.0, 1.0)) for _ in range(n)])
    faces = draw(st.lists(st.tuples(*[st.integers(0, n - 1)] * 3).filter(
        lambda f: len(set(f)) == 3), min_size=1, max_size=6))
    return mesh(name, pts, np.array(faces), RED)


@st.composite
def closed(draw, name: str):
    """A closed mesh: a rotated box or a coarse icosphere."""
    centre = draw(point(-2.0, 2.0))
    if draw(st.booleans()):
        size = [draw(coord(0.25, 2.0)) for _ in range(3)]
        rotation = [draw(st.integers(0, 8)) * 11.25 for _ in range(3)]
        return box(name, centre, size, RED, Transform(rotation=rotation))
    return sphere(name, centre, draw(coord(0.25, 1.0)), RED,
                  subdivisions=draw(st.integers(0, 1)))


def _variant(obj, how: str, seed: int):
    """The same triangles as an unwelded soup (every corner its own vertex) or with some
    triangles' winding reversed."""
    if how == "unwelded":
        tri = obj.triangles.reshape(-1, 3)
        return mesh(obj.name, tri, np.arange(len(tri)).reshape(-1, 3), obj.material)
    if how == "flipped":
        faces = obj.faces.copy()
        flip = np.random.default_rng(seed).random(len(faces)) < 0.5
        faces[flip] = faces[flip][:, ::-1]
        return mesh(obj.name, obj.vertices, faces, obj.material)
    return obj


@st.composite
def objects(draw):
    out = []
    if draw(st.booleans()):
        out.append(plane("floor", point=[0, draw(coord(-1.0, 0.0)), 0], size=[12, 12],
                         material=GREY))
    for i in range(draw(st.integers(1, 4))):
        obj = draw(closed(f"closed{i}")) if draw(st.booleans()) else draw(soup(f"soup{i}"))
        how = draw(st.sampled_from(["as is", "unwelded", "flipped"]))
        out.append(_variant(obj, how, draw(st.integers(0, 99))))
    return out


def light_position():
    """Mostly above the floor and the objects, sometimes among or inside them."""
    return st.tuples(coord(-4.0, 4.0), coord(-1.0, 5.0), coord(-4.0, 4.0)).map(list)


def light_direction():
    """Mostly downward, sometimes grazing or upward."""
    return st.tuples(coord(-1.0, 1.0), coord(-1.0, 0.25), coord(-1.0, 1.0)).map(list).filter(
        lambda v: any(v))


@st.composite
def light(draw):
    kind = draw(st.sampled_from(["point", "directional", "spot"]))
    if kind == "point":
        return PointLight(draw(light_position()))
    if kind == "directional":
        return DirectionalLight(draw(light_direction()))
    position = draw(light_position())
    # a spot aimed at a point near the middle of the scene, or anywhere
    aim = draw(st.one_of(point(-1.0, 1.0), light_direction().map(
        lambda d: [p + x for p, x in zip(position, d)])))
    axis = [a - p for a, p in zip(aim, position)]
    if not any(axis):
        axis = [0.0, -1.0, 0.0]
    return SpotLight(position, axis, cone_angle=draw(st.integers(5, 90)))


@st.composite
def camera(draw):
    """Anywhere, often inside the objects or their volumes; near planes up to 1 unit deep, so
    that they cut volumes and objects."""
    above = st.tuples(coord(-4.0, 4.0), coord(0.5, 4.0), coord(-4.0, 4.0)).map(list)
    eye = draw(st.one_of(above, above, point(-4.0, 4.0)))
    target = draw(point(-1.5, 1.5).filter(lambda t: t != eye))
    up = draw(st.sampled_from([[0, 1, 0], [0, 0, 1], [1, 0, 0]]))
    try:
        return Camera(eye=eye, target=target, up=up, fov_y=draw(st.integers(30, 100)),
                      near=draw(st.sampled_from([0.01, 0.05, 0.3, 1.0])))
    except SceneError:  # up parallel to the view: try the next example
        from hypothesis import reject
        reject()


# |cos| of the angle between a face's plane and the light below which (but above 0) the face is
# edge-on to the light "by rounding": see `rounding_tie`.
TIE_COSINE = 1e-6


def rounding_tie(scene: Scene) -> bool:
    """True when some light lies in the plane of some triangle only up to rounding: a face
    parallel to a directional light, or a point light in a face's plane, with n·l not exactly
    0 but within TIE_COSINE of it (e.g. the side of a box turned 45 degrees under a light at 45
    degrees: the corners come from cos 45° and sin 45°, so n·l is ±1e-17).  Then "n·l > 0"
    (CONVENTIONS.md) is decided by the last bit, in float64 in the ray tracer and float32 on
    the GPU, and the whole face can be lit in one and unlit in the other, interior pixels and
    all: both answers are within rounding of the exact one.  The property excludes these
    inputs; docs/robustness.md lists them as a known limit, and exact ties (axis-aligned, n·l
    exactly 0 in both renderers) stay in: tests/test_robustness_input.py checks them."""
    for obj in scene.objects:
        tri = obj.triangles
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        n_len = np.linalg.norm(n, axis=1)
        keep = n_len > 0
        n, tri = n[keep] / n_len[keep, None], tri[keep]
        for lt in scene.lights:
            if isinstance(lt, DirectionalLight):
                cos = np.abs(n @ lt.direction)[:, None]
            else:
                to = lt.position - tri                                   # (m, 3, 3)
                dist = np.linalg.norm(to, axis=2)
                cos = np.abs(np.einsum("mk,mjk->mj", n, to)) / np.where(dist > 0, dist, 1.0)
            tie = (cos < TIE_COSINE).all(axis=1) & (cos > 0).any(axis=1)
            if tie.any():
                return True
    return False


@st.composite
def scenes(draw):
    width, height = draw(st.sampled_from([(64, 48), (96, 72)]))
    scene = Scene(camera=draw(camera()), objects=draw(objects()),
                  lights=draw(st.lists(light(), min_size=1, max_size=3)),
                  width=width, height=height, name="random")
    assume(not rounding_tie(scene))
    return scene


# ---- large worlds (issue 10): the scenes of tests/worlds.py with their numbers drawn ---------

def _far_offset(low_exp: float, high_exp: float):
    """A translation (3,) of magnitude 10**low_exp .. 10**high_exp, each axis its own sign."""
    return st.tuples(st.floats(low_exp, high_exp), *[st.sampled_from([-1.0, 1.0])] * 3,
                     st.floats(0.2, 1.0), st.floats(0.2, 1.0)).map(
        lambda t: [t[1] * 10 ** t[0], t[2] * t[4] * 10 ** t[0], t[3] * t[5] * 10 ** t[0]])


@st.composite
def far_kerbs(draw):
    """Kerbs translated by 1e3..1e6 under a sun 1..10 degrees up, from any azimuth."""
    from worlds import kerbs
    return kerbs(draw(_far_offset(3.0, 6.0)), elevation=draw(st.floats(1.0, 10.0)),
                 azimuth=draw(st.floats(0.0, 360.0)), turn=draw(st.floats(0.0, 90.0)),
                 height=draw(st.sampled_from([0.02, 0.05, 0.2])), size=(48, 36))


@st.composite
def huge_grounds(draw):
    """The lamp room on a ground quad 1e5..1e7 wide, turned about y, off centre by up to 0.4
    of its width, sometimes with a low sun."""
    from worlds import lamp_room
    ground = 10 ** draw(st.floats(5.0, 7.0))
    shift = [draw(st.floats(-0.4, 0.4)) * ground, 0.0, draw(st.floats(-0.4, 0.4)) * ground]
    sun = draw(st.one_of(st.none(), st.floats(2.0, 30.0)))
    return lamp_room(ground, offset=shift, turn=draw(st.floats(0.0, 90.0)),
                     sun_elevation=sun, size=(48, 36))


@st.composite
def cards_by_lights(draw):
    """A card 2e-5..1e-2 wide beside a point light, its centre 1..1.5 of its half-width away
    (its wedge stays within the floor; the smallest, 1e-5 away, is twice the light margin
    here: `tolerances.light_margin`, ~6e-6 with the light 3 from the eye), tilted, at the
    origin or 1e3..1e4 away."""
    from worlds import card_by_light
    card = 2 * 10 ** draw(st.floats(-5.0, -2.0))
    gap = card / 2 * draw(st.floats(1.0, 1.5))
    offset = draw(st.one_of(st.just([0.0, 0.0, 0.0]), _far_offset(3.0, 4.0)))
    return card_by_light(card, gap, offset=offset, tilt=draw(st.floats(0.0, 40.0)),
                         size=(48, 36))


@st.composite
def grazing_creases(draw):
    """An almost flat concave crease rising 0.05..5 degrees, the sun 0.3..0.9 of that above
    the floor, rotated anyhow, at the origin or up to 1e4 away."""
    from worlds import grazing_crease
    rise = 10 ** draw(st.floats(np.log10(0.05), np.log10(5.0)))
    elevation = rise * draw(st.floats(0.3, 0.9))
    rotation = [draw(st.floats(-180.0, 180.0)) for _ in range(3)]
    offset = draw(st.one_of(st.just([0.0, 0.0, 0.0]), _far_offset(2.0, 4.0)))
    return grazing_crease(rise, elevation, rotation=rotation, offset=offset, size=(48, 36))


@st.composite
def huge_ground_views(draw):
    """`huge_grounds` seen by a random camera a few units from the room (1e5..1e7 wide ground
    quads lost coverage at the image border in the rasterizer under such cameras: issue 10)."""
    scene = draw(huge_grounds())
    eye = [draw(st.floats(-5.0, 5.0)), draw(st.floats(0.2, 6.0)), draw(st.floats(-5.0, 5.0))]
    target = [draw(st.floats(-5.0, 5.0)), draw(st.floats(-1.0, 1.5)),
              draw(st.floats(-5.0, 5.0))]
    assume(np.hypot(eye[0] - target[0], eye[2] - target[2]) > 1e-3)  # not looking along up
    return scene.replace(camera=Camera(eye=eye, target=target, fov_y=draw(st.floats(30.0, 90.0))))


# ---- grazing light, far from the origin (issue 31): every margin of the masks ----------------

def translated(scene: Scene, offset) -> Scene:
    """`scene` moved by offset (3,): objects, lights and camera (area lights keep their
    samples' layout: their centres move)."""
    from shadowvol.scene import AreaLight
    o = np.asarray(offset, float)
    objects = [mesh(ob.name, ob.vertices + o, ob.faces, ob.material) for ob in scene.objects]
    lights = []
    for lt in scene.lights:
        if isinstance(lt, AreaLight):
            lights.append(dataclasses.replace(lt, center=lt.center + o))
        elif isinstance(lt, DirectionalLight):
            lights.append(lt)
        else:
            lights.append(dataclasses.replace(lt, position=lt.position + o))
    camera = dataclasses.replace(scene.camera, eye=scene.camera.eye + o,
                                 target=scene.camera.target + o)
    return scene.replace(objects=objects, lights=lights, camera=camera)


def offsets(high_exp: float = 5.0):
    """No translation, or one of magnitude 10**2 .. 10**high_exp."""
    return st.one_of(st.just([0.0, 0.0, 0.0]), _far_offset(2.0, high_exp))


@st.composite
def grazing_light(draw, objects):
    """A light at n·l̂ 1e-4 .. 0.1 above the floor (directional, or a point light 2..6 away),
    or a point light 1e-5 .. 1e-3 off a face of one of `objects`, on either side."""
    kind = draw(st.sampled_from(["directional", "point", "by a face"]))
    sin_e = 10 ** draw(st.floats(-4.0, -1.0))
    phi = draw(st.floats(0.0, 2 * np.pi))
    flat = np.array([np.cos(phi), 0.0, np.sin(phi)]) * np.sqrt(1 - sin_e ** 2)
    toward = flat + [0.0, sin_e, 0.0]
    if kind == "directional":
        return DirectionalLight(-toward)
    if kind == "point":
        return PointLight(draw(st.floats(2.0, 6.0)) * toward)
    obj = objects[draw(st.integers(0, len(objects) - 1))]
    tri = obj.triangles[draw(st.integers(0, len(obj.triangles) - 1))]
    n = np.cross(tri[1] - tri[0], tri[2] - tri[0])
    assume(np.linalg.norm(n) > 1e-6)
    gap = 10 ** draw(st.floats(-5.0, -3.0)) * draw(st.sampled_from([-1.0, 1.0]))
    return PointLight(tri.mean(axis=0) + gap * n / np.linalg.norm(n))


@st.composite
def close_up(draw, objects):
    """A camera 0.01 .. 3 from where a face of an object meets the floor (y = 0), looking at
    it through a lens of 0.01 .. 20 degrees: where a grazing light's lift would skip the
    face."""
    obj = objects[draw(st.integers(1, len(objects) - 1))]
    tri = obj.triangles
    a, b = tri, np.roll(tri, 1, axis=1)
    crossing = np.argwhere((a[..., 1] < 0) & (b[..., 1] > 0))
    assume(len(crossing) > 0)
    m, e = crossing[draw(st.integers(0, len(crossing) - 1))]
    p, q = a[m, e], b[m, e]
    target = p + (q - p) * (-p[1] / (q[1] - p[1]))
    back = np.array([draw(st.floats(-1.0, 1.0)), draw(st.floats(0.2, 1.0)),
                     draw(st.floats(-1.0, 1.0))])
    assume(np.hypot(back[0], back[2]) > 0.05)  # not looking straight down the up axis
    eye = target + 10 ** draw(st.floats(-2.0, 0.5)) * back / np.linalg.norm(back)
    return Camera(eye=eye, target=target, fov_y=10 ** draw(st.floats(-2.0, 1.3)),
                  near=float(np.linalg.norm(eye - target)) * 0.01)


@st.composite
def grazing_scenes(draw, size=(40, 30)):
    """A floor, 1..3 closed or open objects, 1..2 grazing lights (`grazing_light`), a random
    camera, the whole translated by up to 1e5 (`offsets`)."""
    objs = [plane("floor", point=[0, 0, 0], size=[12, 12], material=GREY)]
    for i in range(draw(st.integers(1, 3))):
        obj = draw(closed(f"closed{i}")) if draw(st.booleans()) else draw(soup(f"soup{i}"))
        objs.append(_variant(obj, draw(st.sampled_from(["as is", "unwelded", "flipped"])),
                             draw(st.integers(0, 99))))
    lights = [draw(grazing_light(objs)) for _ in range(draw(st.integers(1, 2)))]
    scene = Scene(camera=draw(st.one_of(camera(), close_up(objs))), objects=objs,
                  lights=lights, width=size[0], height=size[1], name="grazing")
    assume(not rounding_tie(scene))
    return translated(scene, draw(offsets()))


@st.composite
def area_light(draw, objects):
    """A rect, disk or sphere light of 1..16 samples, anywhere `light_position` puts lights,
    grazing the floor (its centre 1e-3 .. 0.1 above y = 0), or 1e-3 off a face of one of
    `objects`."""
    from shadowvol.scene import AreaLight
    shape = draw(st.sampled_from(["rect", "disk", "sphere"]))
    where = draw(st.sampled_from(["anywhere", "grazing", "by a face"]))
    if where == "anywhere":
        centre = np.array(draw(light_position()), float)
    elif where == "grazing":
        centre = np.array([draw(coord(-4.0, 4.0)), 10 ** draw(st.floats(-3.0, -1.0)),
                           draw(coord(-4.0, 4.0))])
    else:
        obj = objects[draw(st.integers(0, len(objects) - 1))]
        tri = obj.triangles[draw(st.integers(0, len(obj.triangles) - 1))]
        n = np.cross(tri[1] - tri[0], tri[2] - tri[0])
        assume(np.linalg.norm(n) > 1e-6)
        centre = tri.mean(axis=0) + 1e-3 * draw(st.sampled_from([-1.0, 1.0])) * n / \
            np.linalg.norm(n)
    kw = dict(samples=draw(st.sampled_from([1, 2, 4, 6, 9, 16])),
              pattern=draw(st.sampled_from(["stratified", "halton"])),
              seed=draw(st.integers(0, 9)))
    if shape == "sphere":
        return AreaLight("sphere", centre, radius=draw(coord(0.0625, 1.0)), **kw)
    normal = draw(direction())
    if shape == "rect":
        return AreaLight("rect", centre, normal=normal, size=[draw(coord(0.0625, 1.5)),
                                                              draw(coord(0.0625, 1.5))], **kw)
    return AreaLight("disk", centre, normal=normal, radius=draw(coord(0.0625, 1.0)), **kw)


@st.composite
def area_light_scenes(draw, size=(32, 24)):
    """`objects` (closed, open and non-manifold casters, a floor or not) under 1..2 area
    lights (`area_light`), a random `camera` (often inside an object or its volumes), the
    whole translated by up to 1e5 (`offsets`)."""
    objs = draw(objects())
    lights = [draw(area_light(objs)) for _ in range(draw(st.integers(1, 2)))]
    scene = Scene(camera=draw(camera()), objects=objs, lights=lights, width=size[0],
                  height=size[1], name="soft")
    assume(not any(rounding_tie(scene.replace(lights=lt.hard)) for lt in lights))
    return translated(scene, draw(offsets()))
