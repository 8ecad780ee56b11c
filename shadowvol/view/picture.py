"""The picture of a view state: the same function for the window and for an offscreen check.

`frame(renderer, state)` renders `state` with `renderer` (any context: the window's or EGL) and
returns (H, W, 3) uint8 sRGB, the light marker drawn when `state.marker`.
"""

from __future__ import annotations

import numpy as np

from shadowvol import pictures
from shadowvol.course import slides, volume_roles
from shadowvol.io import encode_srgb
from shadowvol.view.state import ViewState, hard_view, scene_of

MARKER_LAYOUT = slides.Layout(1920, 1080)   # marker sizes as on a 1080p slide


def frame(renderer, state: ViewState, planar=None) -> np.ndarray:
    """(H, W, 3) uint8: `state` in its mode.  `planar`: a PlanarShadows on `renderer` (made
    by the caller; needed for the "planar" mode)."""
    scene = scene_of(renderer.scene, state)
    cam, lights, method = state.camera, state.lights, state.method
    if state.mode == "roles":
        image = encode_srgb(renderer.volume_view(method, camera=cam, lights=lights))
    elif state.mode == "stencil":  # an area light: its centre sample's counts
        result = renderer.render(method, camera=cam, lights=hard_view(lights), stencil=True)
        image = pictures.heat_map(result.stencil[state.probe_light].astype(np.int16),
                                  encode_srgb(result.image)) if len(lights) else \
            encode_srgb(result.image)
    elif state.mode == "planar":
        image = encode_srgb(planar.render(camera=cam, lights=hard_view(lights)).image)
    elif state.mode == "raytraced":
        # split screen at the same camera: the raster's left half beside the ray tracer's
        # right half, so a shadow edge crossing the divider shows both renderers at once
        import raytrace
        image = encode_srgb(renderer.render(method, camera=cam, lights=lights).image)
        image = _split(encode_srgb(renderer.render(method, camera=cam, lights=lights).image),
                       encode_srgb(raytrace.render(scene, progress=False)), "raster",
                       "ray traced")
    elif state.mode == "exact":
        image = _split(encode_srgb(renderer.render(method, camera=cam, lights=lights).image),
                       exact_image(scene), f"sampled, N = {_samples(lights)}", "exact")
    else:
        image = encode_srgb(renderer.render(method, camera=cam, lights=lights).image)
        if state.mode == "silhouettes" and lights:
            image, _ = volume_roles.draw_silhouettes(
                image, scene, hard_view(lights)[state.probe_light].homogeneous,
                _layout(scene))
    if state.marker:
        image = slides.mark_lights(image, scene, _layout(scene))
    return image


def exact_image(scene) -> np.ndarray:
    """(H, W, 3) uint8: `scene` by the ray tracer's analytic integrator: each area light's
    diffuse light from its exact visible region, no sample noise (`raytrace.outlook.analytic`;
    MissingExtra without shapely, SceneError for a sphere light)."""
    from raytrace.outlook import analytic
    return encode_srgb(analytic.render(scene))


def _samples(lights) -> str:
    """The samples shown of the area lights, e.g. "16" or "16, 4"."""
    return ", ".join(str(lt.samples) for lt in lights if hasattr(lt, "positions")) or "-"


def _split(left: np.ndarray, right: np.ndarray, left_label: str, right_label: str
           ) -> np.ndarray:
    """Split screen: `left`'s left half beside `right`'s right half, so an edge crossing the
    divider shows both at once, each half labelled."""
    half = left.shape[1] // 2
    image = left.copy()
    image[:, half:] = right[:, half:]
    image[:, half - 1:half + 1] = (255, 255, 255)
    return _label(_label(image, left_label, 6), right_label, half + 6)


def _label(image: np.ndarray, text: str, x: int) -> np.ndarray:
    from PIL import Image, ImageDraw

    img = Image.fromarray(image)
    ImageDraw.Draw(img).text((x, 4), text, fill=(255, 255, 255), font=slides.font(14),
                             stroke_width=2, stroke_fill=(0, 0, 0))
    return np.asarray(img, np.uint8)


def _layout(scene) -> slides.Layout:
    """Marker and line sizes for an image of the scene's height (as on a slide that tall)."""
    return slides.Layout(round(scene.height * 16 / 9), scene.height)
