"""A trimesh.Scene -> our Scene, with its camera: `from_trimesh` (as `from_pyrender` converts
a pyrender.Scene, `shadowvol.compare.pyrender_peer`).

trimesh keeps a camera as intrinsics and a pose: `scene.camera` (resolution (W, H), focal
(fx, fy) in pixels, the principal point at resolution / 2: its `K`) and `scene.camera_transform`
(camera to world, OpenGL axes: the camera looks down its -z).  Those are exactly the matrix
form of our `Camera` (docs/CONVENTIONS.md, "Camera matrices"), so they are taken as they are:
the frame's K and camera_to_world are trimesh's.
"""

from __future__ import annotations

import math

import numpy as np

from shadowvol.scene import (
    Camera,
    DirectionalLight,
    Material,
    Object,
    PointLight,
    Scene,
    SceneError,
    SpotLight,
)
from shadowvol.scenefile_mesh import _scene_parts, part_material

# The light a scene without lights gets, in the camera's axes (x right, y up, z back): from
# above, behind the camera's left shoulder, travelling right, down and forward.
DEFAULT_LIGHT_IN_CAMERA = np.array([0.3, -1.0, -0.5])


def from_trimesh(scene, width: int | None = None, height: int | None = None,
                 name: str | None = None, near: float | None = None) -> Scene:
    """A trimesh.Scene -> our Scene, seen by the scene's own camera.

    - Camera: the scene must have one (`scene.has_camera`; trimesh would otherwise make one up
      when asked, so it is not asked).  fx, fy = `camera.focal`, cx, cy = resolution / 2 (its
      `K`), camera_to_world = `scene.camera_transform` (which must be rigid), near =
      `camera.z_near` unless `near` is given; the image is the camera's resolution (W, H),
      unless width and height are given: the intrinsics then scale with the image
      (`Scene.replace`).  z_far is dropped (we have no far plane).
    - Geometry: every instance of a triangle mesh in the scene graph, its world transform
      applied, one Object per instance named after its node, depth-first in the graph's
      order (as a glTF's parts load from a scene file).  Point clouds and paths have no area
      and are left out.  Material: the mesh's glTF base colour as its diffuse colour where it
      has one, else the default (textures are not read).
    - Lights: the scene's own (`scene.lights` where it was set; trimesh's automatic lights
      are not made): directional (travelling along its node's -z), point (at its node's
      origin) and spot (cone_angle = the outer cone angle), colour = its RGB / 255, intensity
      as given (our lights have no distance fall-off, so a glTF candela value is a relative
      factor here).  A scene without lights gets one directional light of intensity 1 from
      above and behind the camera (DEFAULT_LIGHT_IN_CAMERA, turned into the world by the
      camera's pose).
    Raises SceneError naming what is missing or wrong.
    """
    if not getattr(scene, "has_camera", False):
        raise SceneError("camera", "the trimesh scene has no camera (set one: "
                                   "scene.set_camera() or scene.camera = ...)")
    cam = scene.camera
    resolution = np.asarray(cam.resolution, np.int64)
    K = np.asarray(cam.K, np.float64)
    pose = np.asarray(scene.camera_transform, np.float64)
    try:
        camera = Camera(fx=K[0, 0], fy=K[1, 1], cx=K[0, 2], cy=K[1, 2], camera_to_world=pose,
                        near=cam.z_near if near is None else near)
    except SceneError as exc:
        raise exc.under("camera") from None
    parts = _scene_parts(scene, [], {})   # no texture read from a file: the visuals trimesh made
    objects = [Object(part.node, part.vertices, part.faces,
                      part_material(Material(), part, False))
               for part in parts if len(part.faces)]
    if not objects:
        raise SceneError("geometry", "the trimesh scene holds no triangles")
    lights = _lights(scene) or [DirectionalLight(pose[:3, :3] @ DEFAULT_LIGHT_IN_CAMERA)]
    out = Scene(camera=camera, objects=objects, lights=lights, width=int(resolution[0]),
                height=int(resolution[1]), name=name or "trimesh")
    if width is not None or height is not None:
        out = out.replace(width=width or out.width, height=height or out.height)
    return out


def _lights(scene) -> list:
    """The lights the trimesh scene was given (not trimesh's automatic ones), in its order."""
    from trimesh.scene import lighting

    out = []
    for light in getattr(scene, "_lights", None) or []:
        pose = np.asarray(scene.graph[light.name][0], np.float64)
        color = np.asarray(light.color, np.float64)[:3] / 255.0
        intensity = float(light.intensity)
        position, direction = pose[:3, 3], -pose[:3, 2]
        if isinstance(light, lighting.DirectionalLight):
            out.append(DirectionalLight(direction, color, intensity))
        elif isinstance(light, lighting.SpotLight):
            out.append(SpotLight(position, direction, math.degrees(light.outerConeAngle),
                                 color, intensity))
        elif isinstance(light, lighting.PointLight):
            out.append(PointLight(position, color, intensity))
    return out
