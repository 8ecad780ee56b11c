"""What the viewer shows, as plain data: the camera, the lights, the counting method, the mode.

A `ViewState` is immutable; every key and drag makes a new one (`orbit`, `pan`, `zoom`,
`drag_light`, `dataclasses.replace`).  The frame of a state is `picture.frame` of it, the same
in the window and offscreen.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from shadowvol.cameras import camera_to_world, pinhole
from shadowvol.raster.methods import METHODS
from shadowvol.scene import AreaLight, Camera, DirectionalLight, Scene

MODES = ("shaded", "roles", "silhouettes", "stencil", "planar", "raytraced", "exact")
ORBIT_PER_PIXEL = 0.01       # radians of orbit per pixel dragged
ZOOM_PER_STEP = 0.9          # the eye's distance scales by this per scroll step
MIN_PITCH = 0.02             # radians kept between the view direction and the up axis
RESIZE_PER_STEP = 1.25       # an area light's size scales by this per key press
# An area light is shown with at most this many samples (each is a full stencil count, so the
# frame costs about one volume pass per sample); `,` and `.` halve and double it, up to the
# scene's own N.  The window says how many it shows.
VIEW_SAMPLES = 16


@dataclass(frozen=True)
class ViewState:
    camera: Camera
    lights: tuple
    method: str = "auto"
    mode: str = "shaded"
    marker: bool = True           # the light marker drawn over the frame
    help: bool = True             # the help text in the side panel
    probe_light: int = 0          # which light the count probe and the stencil view use

    scene_lights: tuple = ()      # the scene's own lights (an area light's full N)

    @classmethod
    def of(cls, scene: Scene) -> "ViewState":
        lights = tuple(scene.lights)
        shown = tuple(with_samples(lt, min(VIEW_SAMPLES, lt.samples))
                      if isinstance(lt, AreaLight) else lt for lt in lights)
        return cls(camera=scene.camera, lights=shown, scene_lights=lights)


def _moved(cam: Camera, eye, target) -> Camera:
    """`cam` looking from `eye` at `target`.  A camera given by matrices keeps its intrinsics
    and gets the look-at pose (its own up axis as up); its target is one unit ahead of it."""
    if not cam.matrix_form:
        return replace(cam, eye=eye, target=target)
    pose = camera_to_world(Camera(eye=eye, target=target, up=cam.up))
    return replace(cam, camera_to_world=pose, eye=None, target=None, up=None)


def _pixel(cam: Camera, height: int) -> np.ndarray:
    """(2,) the width and height of a pixel at unit depth: 1 / fx, 1 / fy (both
    2 tan(fov_y / 2) / height for a look-at camera)."""
    fx, fy, _, _ = pinhole(cam, 1, height)
    return np.array([1.0 / fx, 1.0 / fy])


def _basis(camera: Camera):
    fwd = camera.target - camera.eye
    fwd = fwd / np.linalg.norm(fwd)
    right = np.cross(fwd, camera.up)
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    return fwd, right, up


def orbit(state: ViewState, dx: float, dy: float) -> ViewState:
    """Turn the eye around the target: dx pixels about the up axis, dy pixels up or down."""
    cam = state.camera
    up = cam.up / np.linalg.norm(cam.up)
    offset = cam.eye - cam.target
    r = np.linalg.norm(offset)
    yaw = -dx * ORBIT_PER_PIXEL
    # rotate about up (Rodrigues)
    k = up
    offset = (offset * np.cos(yaw) + np.cross(k, offset) * np.sin(yaw)
              + k * (k @ offset) * (1 - np.cos(yaw)))
    pitch = np.arccos(np.clip((offset @ up) / r, -1, 1))
    pitch = np.clip(pitch + dy * ORBIT_PER_PIXEL, MIN_PITCH, np.pi - MIN_PITCH)
    flat = offset - (offset @ up) * up
    flat = flat / np.linalg.norm(flat)
    offset = r * (np.sin(pitch) * flat + np.cos(pitch) * up)
    return replace(state, camera=_moved(cam, cam.target + offset, cam.target))


def pan(state: ViewState, dx: float, dy: float, height: int) -> ViewState:
    """Slide eye and target along the view plane by dx, dy pixels (at the target's depth)."""
    cam = state.camera
    _, right, up = _basis(cam)
    dist = np.linalg.norm(cam.target - cam.eye)
    px, py = dist * _pixel(cam, height)
    move = -dx * px * right - dy * py * up
    return replace(state, camera=_moved(cam, cam.eye + move, cam.target + move))


def zoom(state: ViewState, steps: float) -> ViewState:
    """Move the eye toward the target (steps > 0) or away."""
    cam = state.camera
    offset = (cam.eye - cam.target) * ZOOM_PER_STEP ** steps
    return replace(state, camera=_moved(cam, cam.target + offset, cam.target))


def drag_light(state: ViewState, dx: float, dy: float, height: int) -> ViewState:
    """Move the probed light in the view plane at its own depth (a directional light turns)."""
    i = state.probe_light
    if not state.lights:
        return state
    light = state.lights[i]
    cam = state.camera
    fwd, right, up = _basis(cam)
    if isinstance(light, DirectionalLight):
        d = light.direction + (dx * right - dy * up) * ORBIT_PER_PIXEL
        new = replace(light, direction=d / np.linalg.norm(d))
    elif isinstance(light, AreaLight):  # its centre moves; its samples are made anew
        depth = max((light.center - cam.eye) @ fwd, cam.near)
        px, py = depth * _pixel(cam, height)
        new = replace(light, center=light.center + dx * px * right - dy * py * up)
    else:
        depth = max((light.position - cam.eye) @ fwd, cam.near)
        px, py = depth * _pixel(cam, height)
        new = replace(light, position=light.position + dx * px * right - dy * py * up)
    # the cached homogeneous form belongs to the old position: a fresh light is made
    lights = list(state.lights)
    lights[i] = new
    return replace(state, lights=tuple(lights))


def with_samples(light, samples: int):
    """An area light with `samples` samples (at least 1); other lights as they are."""
    if not isinstance(light, AreaLight):
        return light
    return replace(light, samples=max(1, int(samples)))


def change_samples(state: ViewState, factor: float) -> ViewState:
    """The probed area light with its samples scaled by `factor`, between 1 and the scene's N."""
    i = state.probe_light
    if not state.lights or not isinstance(state.lights[i], AreaLight):
        return state
    light = state.lights[i]
    full = state.scene_lights[i].samples if i < len(state.scene_lights) and \
        isinstance(state.scene_lights[i], AreaLight) else light.samples
    n = min(full, max(1, round(light.samples * factor)))
    lights = list(state.lights)
    lights[i] = with_samples(light, n)
    return replace(state, lights=tuple(lights))


def resize_light(state: ViewState, steps: int) -> ViewState:
    """Grow (steps > 0) or shrink the probed light if it is an area light: its size (rect),
    radius (disk, sphere) or vertices about its centre (polygon) scale by RESIZE_PER_STEP per
    step, with the same number of samples made anew (the umbra shrinks and the penumbra widens
    as it grows).  Other lights stay."""
    if not state.lights or not isinstance(state.lights[state.probe_light], AreaLight):
        return state
    light = state.lights[state.probe_light]
    scale = RESIZE_PER_STEP ** steps
    if light.shape == "polygon":
        new = replace(light, vertices=light.center + (light.vertices - light.center) * scale)
    else:
        new = (replace(light, size=light.size * scale) if light.shape == "rect"
               else replace(light, radius=light.radius * scale))
    lights = list(state.lights)
    lights[state.probe_light] = new
    return replace(state, lights=tuple(lights))


def hard_view(lights) -> tuple:
    """The lights as the stencil, silhouette, planar and probe views count them: an area light
    by its sample nearest its centre at the whole light's power (each sample is counted as a
    point light), the others as they are."""
    out = []
    for light in lights:
        if isinstance(light, AreaLight):
            nearest = int(np.argmin(np.linalg.norm(light.positions - light.center, axis=1)))
            light = replace(light.hard[nearest], intensity=light.intensity)
        out.append(light)
    return tuple(out)


def scene_of(scene: Scene, state: ViewState) -> Scene:
    """The scene as the state shows it (its camera and lights)."""
    return scene.replace(camera=state.camera, lights=state.lights)
