"""A convex object's whole shadow (`occluders.Convex.shadows`): from an eye beyond the object,
on the light's plane, it is the convex hull of every corner's shadow (shapely's hull of the
corners carried in float64 here, the witness); numba's kernel and numpy's path give the same
bytes; and `exact_soft` measures a pixel whose one shadow is such an object's from its
corners alone, with no GEOS, to the bytes GEOS's path gives (`unions.pixel_unions`)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

pytest.importorskip("shapely")
import shapely  # noqa: E402

from raytrace import exact_soft, occluders, unions  # noqa: E402
from raytrace.lightshapes import frame_light  # noqa: E402
from raytrace.occluders import objects  # noqa: E402
from shadowvol import Camera, Material, Scene  # noqa: E402
from shadowvol.primitives import mesh, plane  # noqa: E402
from shadowvol.scene import AreaLight  # noqa: E402


def _body(kind: str, rng) -> trimesh.Trimesh:
    if kind == "ball":
        body = trimesh.creation.icosphere(subdivisions=int(rng.integers(0, 4)))
    elif kind == "box":
        body = trimesh.creation.box(extents=rng.uniform(0.2, 1.5, 3))
    else:                                  # the hull of random points: faces of every shape
        body = trimesh.convex.convex_hull(rng.normal(size=(int(rng.integers(8, 60)), 3)))
    turn = trimesh.transformations.random_rotation_matrix(rng.random(3))
    body.apply_transform(turn)
    body.apply_scale(rng.uniform(0.2, 1.0))
    return body


def _case(seed: int):
    """A convex body (`Convex`), a rect light above it (framed) and eyes below it: every
    corner strictly between an eye's parallel plane and the light's."""
    rng = np.random.default_rng(seed)
    body = _body(("ball", "box", "hull")[seed % 3], rng)
    corners = np.asarray(body.vertices)[np.asarray(body.faces)]
    convex = objects(corners, np.zeros(len(corners), np.int64)).bodies[0]
    assert convex is not None
    normal = rng.normal(size=3) * 0.3 + [0.0, -1.0, 0.0]
    light = frame_light(AreaLight("rect", [0.0, 3.0, 0.0], normal=normal, size=[1.0, 1.0],
                                  samples=4), np.zeros(3), "lights[0]")
    height = (convex.points - light.center) @ light.normal
    eyes = light.center + light.normal * (height.max() + rng.uniform(1e-3, 3.0, (400, 1)))
    eyes += rng.normal(size=(400, 2)) * 2.0 @ light.axes
    return convex, light, eyes


def _carried(points: np.ndarray, eye: np.ndarray, light) -> np.ndarray:
    """points (V, 3) carried from eye (3,) onto the light's plane, in its axes (V, 2)."""
    ray = points - eye
    t = ((light.center - eye) @ light.normal) / (ray @ light.normal)
    return (eye + t[:, None] * ray - light.center) @ light.axes.T


@pytest.mark.parametrize("seed", range(9))
def test_a_bodys_shadow_is_the_hull_of_every_corners_shadow(seed):
    convex, light, eyes = _case(seed)
    flat, count = convex.shadows(eyes, light)
    assert (count >= 3).all()
    for k, eye in enumerate(eyes):
        corners = flat[k, :count[k]]
        x, y = corners[:, 0], corners[:, 1]
        area = (x * np.roll(y, -1) - np.roll(x, -1) * y).sum() / 2
        every = _carried(convex.points, eye, light)
        hull = shapely.convex_hull(shapely.multipoints(every))
        scale = np.abs(every).max() ** 2
        # counter-clockwise, the hull's area, every hull corner among its corners, and each
        # corner on the hull's outline (an edge-on face adds corners along an edge only)
        assert area == pytest.approx(hull.area, rel=1e-11, abs=1e-13 * scale)
        ring = np.asarray(hull.exterior.coords)[:-1]
        assert np.abs(ring[:, None] - corners[None]).max(axis=2).min(axis=1).max() <= \
            1e-12 * np.sqrt(scale)
        assert shapely.distance(shapely.points(corners), hull.exterior).max() <= \
            1e-11 * np.sqrt(scale)
        u, w = np.roll(corners, -1, 0) - corners, np.roll(corners, -2, 0) - corners
        turns = u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0]
        assert turns.min() >= -1e-12 * scale


@pytest.mark.parametrize("seed", range(6))
def test_numba_and_numpy_give_the_same_bytes(seed, monkeypatch):
    pytest.importorskip("numba")
    convex, light, eyes = _case(seed)
    fast = convex.shadows(eyes, light)
    real = occluders.kernels
    monkeypatch.setattr(occluders, "kernels",
                        lambda name="exactkernels": None if name == "occluderkernels"
                        else real(name))
    slow = convex.shadows(eyes, light)
    assert fast[0].shape == slow[0].shape
    assert fast[0].tobytes() == slow[0].tobytes() and np.array_equal(fast[1], slow[1])


def _scene(size: int = 40) -> Scene:
    ball = trimesh.creation.icosphere(subdivisions=2, radius=0.5)
    box = trimesh.creation.box(extents=[0.6, 0.4, 0.6])
    matte = Material(diffuse=[0.8, 0.8, 0.8])
    return Scene(camera=Camera(eye=[0.0, 4.0, 5.0], target=[0.0, 0.0, 0.0], fov_y=40.0),
                 objects=[plane("floor", size=[8, 8], material=matte),
                          mesh("ball", ball.vertices + [-0.6, 1.2, 0.0], ball.faces,
                               material=matte),
                          mesh("box", box.vertices + [0.7, 1.0, 0.3], box.faces,
                               material=matte)],
                 lights=[AreaLight("rect", [0.0, 3.0, 0.0], normal=[0.1, -1.0, 0.0],
                                   size=[1.2, 1.0], samples=4)],
                 width=size, height=size, ambient=[0, 0, 0])


def test_a_pixel_whose_one_shadow_is_a_body_is_measured_from_its_corners(monkeypatch):
    """Given by its corners (no GEOS polygon) or by GEOS's polygon of them, the same bytes;
    the first path taken by most penumbra pixels here, and the union None there."""
    scene = _scene()
    real, alone = unions.pixel_unions, []

    def spy(*args):
        union, (one, rows, sizes) = real(*args)
        alone.append(int(((one >= 0) & (union == None)).sum()))  # noqa: E711 (object array)
        return union, (one, rows, sizes)

    monkeypatch.setattr(exact_soft, "pixel_unions", spy)
    fast = exact_soft.exact_visibility(scene)
    v = fast.visibility[0]
    assert sum(alone) > 100 and ((v > 0) & (v < 1)).sum() > 100

    def geos(shapely_, bodies, shapes, owner, n, grid, flat, arranged):
        """Every one convex union by GEOS, its corners read back from its polygon."""
        _, (one, _, _) = real(shapely_, bodies, shapes, owner, n, grid, flat, arranged)
        union, _ = real(shapely_, bodies, shapes, owner, n, grid, False, arranged)
        at = np.flatnonzero(one >= 0)
        assert (union[at] != None).all()  # noqa: E711
        one[at] = np.arange(len(at))
        return union, (one, *unions.convex_corners(shapely_, union[at]))

    monkeypatch.setattr(exact_soft, "pixel_unions", geos)
    slow = exact_soft.exact_visibility(scene)
    assert fast.visibility.tobytes() == slow.visibility.tobytes()
    assert fast.irradiance.tobytes() == slow.irradiance.tobytes()
