"""A frame's arrays for the layouts: one render of the image, masks, depth and ids, plus every
light's `casters` and each object's unoccluded silhouette where a layout asks for them."""

from __future__ import annotations

import dataclasses

import numpy as np

from shadowvol.batch.sources import SOURCES
from shadowvol.batch.spec import FrameSpec
from shadowvol.scene import BACKGROUND, Scene

# the frame arrays every layout reads: what `Worker.arrays` makes for these outputs
BASE_OUTPUTS = ["image", "masks", "depth", "object_id"]


def frame_arrays(worker, spec: FrameSpec, scene: Scene, camera, lights, *, casters: bool = False,
                 alone: bool = False) -> dict:
    """The worker's arrays of BASE_OUTPUTS, plus `casters` (L, H, W, K) uint64 of every light
    (`casters_lights`: their indices, every light's) and `alone` (n, H, W) bool: each object's
    coverage drawn without the others (nothing for the background's)."""
    outputs = BASE_OUTPUTS + (["casters"] if casters else [])
    arrays = worker.arrays(dataclasses.replace(spec, outputs=tuple(outputs)), scene, camera,
                           lights)
    arrays["casters_lights"] = list(range(len(lights))) if casters else []
    if alone:   # the stage (category background) is in no dataset's ground truth
        empty = np.zeros((scene.height, scene.width), bool)
        arrays["alone"] = np.stack([empty if obj.label == BACKGROUND else
                                    _alone(worker, spec, scene, camera, obj)
                                    for obj in scene.objects])
    return arrays


def _alone(worker, spec: FrameSpec, scene: Scene, camera, obj) -> np.ndarray:
    """(H, W) bool: where `obj` covers a pixel in a scene of it alone, by the frame's renderer."""
    single = scene.replace(objects=(obj,), lights=(), camera=camera)
    return SOURCES[spec.renderer].alone(worker, spec, single)
