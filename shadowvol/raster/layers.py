"""The rasterizer's intrinsic layers (docs/CONVENTIONS.md, "Intrinsic layers"), each drawn by
the shading pass itself, so that each is exactly what the image's shading computes in float32:

- `ambient`: the frame with no light (ka · base · ambient; the background where nothing is);
- `direct[i]`, `direct_shadowed[i]`: light i alone, without and with its shadows, in a twin
  renderer of the scene with ambient and background 0 (the shading pass starts from
  ka · 0 = 0, so the image is light i's term exactly: the sum over an area light's samples
  that reach the point, for `direct_shadowed`; over all its facing samples for `direct`);
- `shadow_free`: the frame with every light's `shadows` off (ISTD's shadow-free twin, the
  same render: bit-identical to it);
- `albedo`: kd · base (textures and vertex colours), drawn as the ambient term of a twin
  whose materials' ka is their kd, with ambient 1 and background 0 (kd · base · 1 exactly).

Cost (correctness first): 2 frames per light for `direct` and `direct_shadowed`, 1 for
`ambient`, 1 for `shadow_free` and 1 for `albedo`, and for the twins their geometry uploaded
once per frame asked; no new shader.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from shadowvol.frame import LAYERS

# the renderer's switches a twin renderer copies
_SETTINGS = ("cull_back_faces", "check_overflow", "masks_in_stencil")


def shadowless(lights) -> tuple:
    """The lights with `shadows` False."""
    return tuple(dataclasses.replace(light, shadows=False) for light in lights)


def render_layers(renderer, method: str, silhouettes: str, camera, lights, shadows: bool,
                  wanted) -> dict[str, np.ndarray]:
    """The layers `wanted` (names of `shadowvol.frame.LAYERS`) of the frame
    `renderer.render(method, silhouettes, camera=camera, lights=lights, shadows=shadows)`
    draws, by name, (H, W, 3) or (L, H, W, 3) float32."""
    scene = renderer.scene
    lights = tuple(scene.lights if lights is None else lights)
    frame = dict(camera=camera, outputs=("image",))
    out = {}
    if "ambient" in wanted:
        out["ambient"] = renderer.render(method, silhouettes, lights=(), **frame).image
    if "shadow_free" in wanted:
        out["shadow_free"] = renderer.render(method, silhouettes, lights=shadowless(lights),
                                             **frame).image
    if {"direct", "direct_shadowed"} & set(wanted):
        dark = scene.replace(ambient=np.zeros(3), background=np.zeros(3))
        with _twin(renderer, dark) as twin:
            for name, on in (("direct", False), ("direct_shadowed", shadows)):
                if name in wanted:
                    out[name] = _per_light(twin, method, silhouettes, lights, on, frame)
    if "albedo" in wanted:
        objects = [dataclasses.replace(o, material=dataclasses.replace(
            o.material, ambient=o.material.diffuse)) for o in scene.objects]
        white = scene.replace(objects=objects, ambient=np.ones(3), background=np.zeros(3))
        with _twin(renderer, white) as twin:
            out["albedo"] = twin.render(method, silhouettes, lights=(), **frame).image
    return {name: np.array(out[name], np.float32) for name in LAYERS if name in wanted}


def _per_light(twin, method, silhouettes, lights, shadows: bool, frame) -> np.ndarray:
    """(L, H, W, 3) float32: each light alone, drawn by `twin`."""
    H, W = twin.scene.height, twin.scene.width
    out = np.zeros((len(lights), H, W, 3), np.float32)
    for i, light in enumerate(lights):
        out[i] = twin.render(method, silhouettes, lights=(light,), shadows=shadows,
                             **frame).image
    return out


def _twin(renderer, scene):
    """A renderer of `scene` on `renderer`'s context, with its switches."""
    twin = type(renderer)(scene, renderer.ctx)
    for name in _SETTINGS:
        setattr(twin, name, getattr(renderer, name))
    return twin
