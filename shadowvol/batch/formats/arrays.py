"""A frame's arrays for the layouts: one render of the image, masks, depth and ids, plus the
hard lights' `casters` and each object's unoccluded silhouette where a layout asks for them."""

from __future__ import annotations

import numpy as np

from shadowvol.scene import AreaLight, Scene, SceneError

# the frame arrays every layout reads: what `Worker._arrays` makes for these outputs
BASE_OUTPUTS = ["image", "masks", "depth", "object_id"]


def frame_arrays(worker, spec: dict, scene: Scene, camera, lights, *, casters: bool = False,
                 alone: bool = False) -> dict:
    """The worker's arrays of BASE_OUTPUTS, plus `casters` (K, H, W) uint64 of the hard lights
    `casters_lights` (their indices; none when the renderer refuses casters for the scene's
    objects) and `alone` (n, H, W) bool: each object's coverage drawn without the others."""
    hard = [i for i, light in enumerate(lights) if not isinstance(light, AreaLight)]
    arrays = got = None
    if casters and hard and len(hard) == len(lights):  # one render makes them all
        got = arrays = _casters(worker, dict(spec, outputs=BASE_OUTPUTS + ["casters"]), scene,
                                camera, lights)
    if arrays is None:
        arrays = worker._arrays(dict(spec, outputs=BASE_OUTPUTS), scene, camera, lights)
        if casters and hard and len(hard) < len(lights):  # casters of the hard lights alone
            got = _casters(worker, dict(spec, outputs=["casters"]), scene, camera,
                           tuple(lights[i] for i in hard))
    arrays["casters_lights"] = hard if got is not None else []
    if got is not None:
        arrays["casters"] = got["casters"]
    if alone:
        arrays["alone"] = np.stack([_alone(worker, spec, scene, camera, obj)
                                    for obj in scene.objects])
    return arrays


def _casters(worker, spec: dict, scene: Scene, camera, lights) -> dict | None:
    """The worker's arrays, or None when the renderer refuses `casters` for the number of
    objects (its limit; the layout then notes that no light has them)."""
    try:
        return worker._arrays(spec, scene, camera, lights)
    except SceneError as exc:
        if exc.key != "objects":
            raise
        return None


def _alone(worker, spec: dict, scene: Scene, camera, obj) -> np.ndarray:
    """(H, W) bool: where `obj` covers a pixel in a scene of it alone, by the frame's renderer."""
    single = scene.replace(objects=(obj,), lights=(), camera=camera)
    if spec["renderer"] == "raytrace":
        import raytrace

        return raytrace.shadow_masks(single)[1]
    from shadowvol.raster.renderer import Renderer

    with Renderer(single, worker._context()) as renderer:
        return renderer.render(spec["method"], camera=camera, lights=(),
                               outputs=("coverage",)).coverage
