"""shadowvol: exact hard shadows with stencil shadow volumes, headless (moderngl on EGL).

The scene model (`shadowvol.scene`, `shadowvol.scenefile`, `shadowvol.primitives`) imports no GL,
so the ray tracer can share it; the GL renderer is imported on first use of `render`.
"""

from .scene import (Camera, DirectionalLight, Material, Object, PointLight, Scene, SceneError,
                    SpotLight)
from .scenefile import load_scene

__all__ = ["Camera", "DirectionalLight", "Material", "Object", "PointLight", "Scene",
           "SceneError", "SpotLight", "load_scene", "render"]


def __getattr__(name):
    # Deferred so that `import shadowvol.scene` (the ray tracer does) never loads moderngl.
    if name == "render":
        from .renderer import render
        return render
    raise AttributeError(f"module 'shadowvol' has no attribute {name!r}")
