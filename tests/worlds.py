"""Builders for the scenes where a float32 witness is most easily wrong (issue 10): large
translations of small things under a low sun, huge ground quads, occluders right beside a point
light, and grazing light at concave creases.  Shared by the exact tests and their hypothesis
generators (tests/strategies.py); tests/ is on sys.path.

Every builder takes plain numbers, so that a generator only has to draw them.
"""

from __future__ import annotations

import numpy as np

from shadowvol.primitives import Transform, box, mesh, plane
from shadowvol.scene import Camera, DirectionalLight, PointLight, Scene


def sun(elevation: float, azimuth: float) -> DirectionalLight:
    """A directional light `elevation` degrees above the horizon (y up), from `azimuth`."""
    e, a = np.radians(elevation), np.radians(azimuth)
    return DirectionalLight([-np.cos(e) * np.cos(a), -np.sin(e), -np.cos(e) * np.sin(a)])


def kerbs(offset, elevation: float = 3.0, azimuth: float = 20.0, turn: float = 0.0,
          height: float = 0.05, size=(96, 72)) -> Scene:
    """Three 5 cm kerbs (0.15 wide, 3 long) on a 40 x 40 ground, under a sun `elevation`
    degrees up, the whole scene (camera and light too) translated by `offset` (3,) and the
    kerbs turned `turn` degrees about y: their shadows are ~height / tan(elevation) long."""
    t = np.asarray(offset, float)
    spin = Transform(rotation=[0.0, turn, 0.0], translation=t)
    objects = [plane("ground", point=t, size=[40.0, 40.0])]
    for i, x in enumerate((-0.9, 0.0, 0.9)):
        objects.append(box(f"kerb{i}", [x, height / 2, 0.0], [0.15, height, 3.0],
                           transform=spin))
    return Scene(camera=Camera(eye=t + [0.4, 1.6, 2.6], target=t + [0.0, 0.0, -0.2], fov_y=50),
                 objects=objects, lights=[sun(elevation, azimuth)],
                 width=size[0], height=size[1])


def lamp_room(ground: float, offset=(0.0, 0.0, 0.0), turn: float = 0.0, sun_elevation=None,
              size=(96, 72)) -> Scene:
    """A small scene on a square ground quad `ground` wide (turned `turn` degrees about y, its
    centre `offset` away from the room): a 1 m cube, and a point light 1.5 m up inside a lamp
    shade (a 0.3 m box open at the bottom), which lights only a patch of the ground below it.
    With `sun_elevation`, a low sun as well."""
    centre = np.asarray(offset, float)
    quad = plane("ground", point=centre, size=[ground, ground],
                 transform=Transform(rotation=[0.0, turn, 0.0]))
    quad = mesh("ground", quad.vertices, quad.faces)  # the turn about the world's y axis
    shade = box("shade", [0.0, 1.5, 0.0], [0.3, 0.3, 0.3])
    tri = shade.triangles
    keep = ~(np.abs(tri[:, :, 1] - 1.35) < 1e-12).all(axis=1)  # drop the bottom face
    shade = mesh("shade", tri[keep].reshape(-1, 3), np.arange(3 * keep.sum()).reshape(-1, 3))
    lights = [PointLight([0.0, 1.5, 0.0])]
    if sun_elevation is not None:
        lights.append(sun(sun_elevation, 35.0))
    return Scene(camera=Camera(eye=[2.5, 2.8, 3.5], target=[0.0, 0.4, 0.0], fov_y=55),
                 objects=[quad, box("cube", [0.9, 0.5, -0.2], [1.0, 1.0, 1.0]), shade],
                 lights=lights, width=size[0], height=size[1])


def card_by_light(card: float, gap: float, offset=(0.0, 0.0, 0.0), tilt: float = 0.0,
                  size=(96, 72)) -> Scene:
    """A square card `card` wide whose centre is `gap` beside a point light 1 m above a 6 x 6
    floor, between the light and the floor (tilted `tilt` degrees), the whole scene translated
    by `offset`: the card is far thinner than anything else, and its shadow on the floor is a
    wide wedge (the card subtends a large angle from the light)."""
    t = np.asarray(offset, float)
    light = t + [0.0, 1.0, 0.0]
    h = card / 2
    corners = np.array([[-h, 0, -h], [h, 0, -h], [h, 0, h], [-h, 0, h]])
    corners = Transform(rotation=[tilt, 0.0, 0.5 * tilt]).points(corners) + light - [0, gap, 0]
    return Scene(camera=Camera(eye=t + [0.5, 2.5, 3.0], target=t + [0.0, 0.0, 0.0], fov_y=60),
                 objects=[plane("floor", point=t, size=[6.0, 6.0]),
                          mesh("card", corners, [[0, 1, 2], [0, 2, 3]])],
                 lights=[PointLight(light)], width=size[0], height=size[1])


def grazing_crease(rise: float, elevation: float, rotation=(0.0, 0.0, 0.0),
                   offset=(0.0, 0.0, 0.0), size=(96, 72)) -> Scene:
    """A concave crease that is almost flat: a 3 x 4 floor and a 1 x 4 face rising `rise`
    degrees from it on the far side of the hinge (the z axis), lit over the face by a sun
    `elevation` (< rise) degrees above the floor's plane, the whole rotated by `rotation` and
    translated by `offset`.  In exact arithmetic the face shadows the floor from the hinge to
    a line beyond it; a start moved up the segment by more than the face's height escapes it."""
    r = np.radians(rise)
    move = Transform(rotation=rotation, translation=offset)
    floor = np.array([[0, 0, -2], [3, 0, -2], [3, 0, 2], [0, 0, 2]], float)
    up = np.array([-np.cos(r), np.sin(r), 0.0])
    face = np.array([[0, 0, -2], [0, 0, 2], up + [0, 0, 2], up + [0, 0, -2]], float)
    quads = [[0, 1, 2], [0, 2, 3]]
    e = np.radians(elevation)
    light = DirectionalLight(move.vectors(np.array([[np.cos(e), -np.sin(e), 0.07]]))[0])
    eye = move.points(np.array([[2.2, 0.9, 1.6]]))[0]
    target = move.points(np.array([[0.5, 0.0, 0.0]]))[0]
    return Scene(camera=Camera(eye=eye, target=target, fov_y=40, near=0.05),
                 objects=[mesh("floor", move.points(floor), quads),
                          mesh("face", move.points(face), quads)],
                 lights=[light], width=size[0], height=size[1])
