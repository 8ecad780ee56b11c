"""Where a batch frame's arrays come from: the `FrameSource` protocol, one implementation per
renderer (after Kubric's renderer interface), in the table `SOURCES` keyed by a job's
`renderer`.  The worker and the runner read a row; neither tests a renderer's name.

raster    `shadowvol` : the stencil shadow-volume renderer (`raster.Renderer`), on the
            worker's GL context; option `method`
rays      `raytrace`  : the ray tracer (the witness); option `max_depth`
auto      `auto`      : the masks alone, per frame by whichever of the two the cost model of
            `shadowvol.compare.fastest` says is faster on this worker (its GL, Embree's queries;
            a worker renders many frames, so without a process's one-off costs); the frame's
            versions say which (`masks_by`)

GL and the ray tracer are imported when a frame first needs them (a spawned worker sets its
thread counts first).
"""

from __future__ import annotations

from importlib import metadata
from typing import Protocol

import numpy as np

from shadowvol.batch.spec import FrameSpec
from shadowvol import memory
from shadowvol.frame import GROUND_TRUTH, LAYERS, soft_arrays
from shadowvol.scene import hard_lights

# what a batch frame asks `Renderer.render(outputs=...)` for (its OUTPUTS; named here, since
# the worker imports GL only when it first renders)
RASTER_OUTPUTS = ("image", "lit", "coverage", *GROUND_TRUTH, *LAYERS)


def _version(package: str) -> str | None:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return None


class FrameSource(Protocol):
    """One renderer, as a batch worker uses it.  `worker` is the `batch.worker.Worker` that
    renders (its GL context, its Renderers); `wanted` the frame arrays asked for
    (`outputs.fields_of`), `truth` the ground-truth ones among them."""

    def options(self, spec: FrameSpec) -> dict:
        """The renderer's options of a frame, as its manifest line records them."""

    def estimate(self, worker, frame_scene, wanted: set, truth: list,
                 written: tuple) -> memory.Estimate:
        """The memory the frame will take (`shadowvol.memory`)."""

    def arrays(self, worker, spec: FrameSpec, scene, camera, lights, wanted: tuple,
               truth: list) -> dict:
        """The frame's arrays by name (beside the camera and light samples, which the worker
        adds)."""

    def alone(self, worker, spec: FrameSpec, single) -> np.ndarray:
        """(H, W) bool: the coverage of `single`, a scene of one object and no lights."""

    def versions(self, worker) -> dict:
        """The versions of what rendered (for the manifest)."""


class Raster:
    def options(self, spec: FrameSpec) -> dict:
        return {"method": spec.method}

    def estimate(self, worker, frame_scene, wanted, truth, written) -> memory.Estimate:
        import shadowvol.raster.estimate

        asked = tuple(name for name in wanted if name in RASTER_OUTPUTS)
        return shadowvol.raster.estimate.render(frame_scene, asked, written=written, gl_in_host=(
            worker.gl_renderer is None or memory.gl_in_host(worker.gl_renderer)))

    def arrays(self, worker, spec, scene, camera, lights, wanted, truth) -> dict:
        renderer = worker.renderer(spec.scene, scene)
        asked = tuple(name for name in wanted if name in RASTER_OUTPUTS)
        if "counts" in wanted and "lit" not in asked:
            asked += ("lit",)
        result = renderer.render(spec.method, camera=camera, lights=lights, outputs=asked)
        arrays = {name: getattr(result, name) for name in asked}
        if "counts" in wanted:   # what a mask file holds of an area light
            arrays["counts"] = soft_arrays(result.lit_count, result.samples)
        return arrays

    def alone(self, worker, spec, single) -> np.ndarray:
        from shadowvol.raster.renderer import Renderer

        with worker.naming(spec.scene), Renderer(single, worker.context()) as renderer:
            return renderer.render(spec.method, camera=single.camera, lights=(),
                                   outputs=("coverage",)).coverage

    def versions(self, worker) -> dict:
        return {"moderngl": _version("moderngl"), "gl_renderer": worker.gl_renderer}


class Rays:
    def options(self, spec: FrameSpec) -> dict:
        return {"max_depth": spec.max_depth}

    def estimate(self, worker, frame_scene, wanted, truth, written) -> memory.Estimate:
        import raytrace.estimate
        import raytrace.outlook.estimate

        parts = ([raytrace.outlook.estimate.whitted(frame_scene, written=())]
                 if "image" in wanted else [])
        if truth or {"lit", "coverage"} & wanted:
            parts.append(raytrace.estimate.masks(frame_scene, truth, picture=False))
        if set(LAYERS) & wanted:   # its float32 arrays and its tile
            parts.append(raytrace.estimate.masks(frame_scene, LAYERS, picture=False))
            parts.append(raytrace.outlook.estimate.layers(frame_scene))
        return memory.Estimate("the ray tracer", frame_scene.width, frame_scene.height,
                               tuple(t for part in parts for t in part.terms))

    def arrays(self, worker, spec, scene, camera, lights, wanted, truth) -> dict:
        import raytrace

        frame_scene = scene.replace(camera=camera, lights=lights)
        arrays = {}
        if "image" in wanted:
            arrays["image"] = raytrace.render(frame_scene, max_depth=spec.max_depth,
                                              progress=False)
        soft = any(len(hard_lights(lt)) > 1 for lt in lights)
        if truth or (soft and {"lit", "coverage", "counts"} & set(wanted)):
            # the masks and an area light's counts come with it, on the same rays
            gt = raytrace.ground_truth(frame_scene, outputs=truth,
                                       backend=_mask_tracer(worker, frame_scene))
            arrays.update({name: getattr(gt, name) for name in truth},
                          lit=gt.lit, coverage=gt.coverage,
                          counts=soft_arrays(gt.lit_count, gt.samples))
        elif {"lit", "coverage", "counts"} & set(wanted):
            arrays["lit"], arrays["coverage"] = raytrace.shadow_masks(
                frame_scene, _mask_tracer(worker, frame_scene))
            arrays["counts"] = {}
        names = tuple(name for name in LAYERS if name in wanted)
        if names:   # Whitted's depth-0 direct light (`raytrace.outlook.layers`)
            from raytrace.outlook.layers import layers
            arrays.update(layers(frame_scene, names))
        return arrays

    def alone(self, worker, spec, single) -> np.ndarray:
        import raytrace

        return raytrace.shadow_masks(single)[1]

    def versions(self, worker) -> dict:
        return {"embreex": _version("embreex")}


def _mask_tracer(worker, frame_scene):
    """The masks' backend of `frame_scene` (`raytrace.masks.scene_backend`), the worker's last
    one where it still holds: the same objects (by identity: a batch's scene is not edited in
    place; a jittered object is a new one) and the same frame origin (the eye: the backend's
    triangles are the scene's minus it, so a new eye needs a new backend).  Frames from one
    viewpoint (lights or targets varied) share it, and with it `ground_truth`'s per-object
    tracers."""
    from raytrace.masks import scene_backend
    from raytrace.tolerances import frame_origin

    origin = frame_origin(frame_scene)
    kept = getattr(worker, "mask_tracer", None)
    if kept is not None:
        objects, kept_origin, tracer = kept
        if (len(objects) == len(frame_scene.objects) and np.array_equal(kept_origin, origin)
                and all(a is b for a, b in zip(objects, frame_scene.objects))):
            return tracer
    worker.mask_tracer = None   # the old one freed before the new one is built
    tracer = scene_backend(frame_scene)
    worker.mask_tracer = (tuple(frame_scene.objects), origin, tracer)
    return tracer


class Auto:
    def choice(self, worker, frame_scene) -> FrameSource:
        """The source of the frame's masks: the faster renderer here (`fastest.choose_for`;
        no GL on the worker: the ray tracer), said in the worker's `masks_by`."""
        from shadowvol.compare import fastest
        from shadowvol.raster.platform.context import ContextError

        if worker.gl_renderer is None:
            try:
                worker.context()
            except ContextError:   # no GL here: the ray tracer makes the masks
                pass
        worker.masks_by = fastest.choose_for(frame_scene, "auto", worker.gl_renderer,
                                             first=False).renderer
        return SOURCES[worker.masks_by]

    def options(self, spec: FrameSpec) -> dict:
        return {"method": spec.method}

    def estimate(self, worker, frame_scene, wanted, truth, written) -> memory.Estimate:
        return self.choice(worker, frame_scene).estimate(worker, frame_scene, wanted, truth,
                                                         written)

    def arrays(self, worker, spec, scene, camera, lights, wanted, truth) -> dict:
        source = self.choice(worker, scene.replace(camera=camera, lights=lights))
        return source.arrays(worker, spec, scene, camera, lights, wanted, truth)

    def alone(self, worker, spec, single) -> np.ndarray:
        return self.choice(worker, single).alone(worker, spec, single)

    def versions(self, worker) -> dict:
        used = getattr(worker, "masks_by", None)
        return {"masks_by": used, **(SOURCES[used].versions(worker) if used else {})}


SOURCES: dict[str, FrameSource] = {"shadowvol": Raster(), "raytrace": Rays(), "auto": Auto()}
