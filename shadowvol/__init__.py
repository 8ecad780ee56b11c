"""shadowvol: exact hard shadows with stencil shadow volumes, headless (moderngl on EGL).

    import shadowvol
    scene = shadowvol.load_scene(shadowvol.example_scene("cage"))
    result = shadowvol.render(scene)              # image, lit (L, H, W), coverage (H, W)
    shadowvol.save_png("cage.png", result.image)
    shadowvol.save_masks("cage.npz", result)     # masks, camera matrices, ground truth

Importing the package loads nothing but itself (not even numpy): every name is imported on
first use, GL with `Renderer` or `render`, trimesh when a mesh is first read.  The layers are drawn in
docs/ARCHITECTURE.md.
"""

from __future__ import annotations

import importlib

__version__ = "0.2.0"

__all__ = ["Camera", "DirectionalLight", "Material", "Object", "PointLight", "Renderer",
           "Scene", "SceneError", "SpotLight", "__version__", "example_scene", "from_trimesh",
           "load_scene", "render", "save_masks", "save_png", "save_scene", "show"]

# name -> the module that defines it, imported on first access (PEP 562)
_LAZY = {**{name: "shadowvol.scene" for name in ("Camera", "DirectionalLight", "Material",
                                                 "Object", "PointLight", "Scene", "SceneError",
                                                 "SpotLight")},
         "example_scene": "shadowvol.resources",
         "Renderer": "shadowvol.raster.renderer", "render": "shadowvol.raster.renderer",
         "load_scene": "shadowvol.scenefile", "save_scene": "shadowvol.scenefile",
         "from_trimesh": "shadowvol.trimesh_scene",
         "save_png": "shadowvol.io", "save_masks": "shadowvol.frame", "show": "shadowvol.display"}


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'shadowvol' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
