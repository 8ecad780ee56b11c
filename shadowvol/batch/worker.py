"""One batch worker: renders frame specs to encoded output bytes, in whatever process or Ray
actor it lives in.

A worker makes one GL context (on the EGL device chosen by `egl.choose`), on the thread that
first renders, and keeps one long-lived Renderer per scene and size on it, so a scene's geometry
is uploaded once per worker, not per frame.  It never writes files: it returns bytes, and the
parent that owns the output folder writes them (`batch.store`), so the files are the same
whichever worker made them.  GL is imported on first use only (a spawned worker sets its thread
counts first).
"""

from __future__ import annotations

import dataclasses
import os
import platform
import sys
import threading
import time
from collections import OrderedDict
from importlib import metadata

import numpy as np

from shadowvol import __version__, memory, signals
from shadowvol.batch import egl, formats, frames
from shadowvol.batch.outputs import OUTPUTS, fields_of
from shadowvol.cameras import calibration
from shadowvol.errors import RENDER_FAILED, message, status_of
from shadowvol.io import GROUND_TRUTH, soft_arrays
from shadowvol.scene import Camera, Scene, SceneError, hard_lights, light_samples
from shadowvol.scenefile import light_from_dict, load_scene

# what a batch frame asks `Renderer.render(outputs=...)` for (its OUTPUTS; named here, since
# the worker imports GL only when it first renders)
RASTER_OUTPUTS = ("image", "lit", "coverage", *GROUND_TRUTH)

# Renderers kept alive per worker (least recently used released first): a job file that cycles
# through many scenes holds at most this many scenes' geometry on the GPU at once.
MAX_RENDERERS = 4
THREAD_VARIABLES = ("LP_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                    "MKL_NUM_THREADS")


def thread_settings(workers: int, cores: int | None = None) -> dict[str, str]:
    """Environment for one of `workers` processes sharing this machine's cores: the BLAS pools
    get cores // workers threads each (at least 1), and so do llvmpipe's rasterizer threads
    (LP_NUM_THREADS), except that a share of one core is LP_NUM_THREADS=0: llvmpipe then
    rasterizes on the thread that draws, where one rasterizer thread would only add a hand-off
    and a wait per draw call (benchmarks/OPTIMISATIONS.md).  Variables the user has set are
    left as they are."""
    cores = cores or len(os.sched_getaffinity(0))
    share = max(1, cores // max(1, workers))
    values = {name: str(share) for name in THREAD_VARIABLES}
    values["LP_NUM_THREADS"] = str(share if share > 1 else 0)
    return {name: value for name, value in values.items() if name not in os.environ}


def _version(package: str) -> str | None:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return None


def light_dict(light) -> dict:
    """A light as plain data in the scene-file schema (for the manifest): its type and fields."""
    kind = type(light).__name__.removesuffix("Light").lower()
    out = {"type": kind}
    for f in dataclasses.fields(light):
        value = getattr(light, f.name)
        out[f.name] = value.tolist() if isinstance(value, np.ndarray) else value
    return out


def camera_dict(camera: Camera) -> dict:
    return {"eye": camera.eye.tolist(), "target": camera.target.tolist(),
            "up": camera.up.tolist(), "fov_y": camera.fov_y, "near": camera.near}


class Worker:
    """Renders frame specs of the scenes `scenes` (scene key -> file path or Scene).

    egl_device: None, "auto" or an index (see `egl.choose`), resolved when the context is made.
    Not thread-safe: one thread renders (the one that made the context).
    """

    def __init__(self, scenes: dict, egl_device=None, label: str = "worker", log=None,
                 budget: int | str | None = None):
        self.scenes = scenes
        # each frame's memory budget in bytes, read once (`memory.budget`: the environment
        # or the machine's memory when None)
        self.budget = memory.budget(budget)
        self.egl_device = egl_device
        self.label = label
        self.log = log if log is not None else (lambda text: print(text, file=sys.stderr,
                                                                    flush=True))
        self._loaded: dict[str, Scene | Exception] = {}
        self._renderers: OrderedDict = OrderedDict()
        self._ctx = None
        self._thread = None
        self.device = None       # "EGL device 0 (...)" once a context exists
        self.gl_renderer = None

    # -- scenes and renderers ------------------------------------------------------------
    def scene(self, key: str) -> Scene:
        if key not in self._loaded:
            source = self.scenes[key]
            try:
                self._loaded[key] = source if isinstance(source, Scene) else load_scene(source)
            except Exception as exc:  # noqa: BLE001 - recorded per frame, never retried here
                self._loaded[key] = exc
        found = self._loaded[key]
        if isinstance(found, Exception):
            raise found
        return found

    def _context(self):
        from shadowvol.raster.context import check_not_forked, create_context

        if self._ctx is None:
            check_not_forked()
            index, why = egl.choose(self.egl_device)
            self._ctx = create_context(device=index)
            self._thread = threading.get_ident()
            self.gl_renderer = self._ctx.info.get("GL_RENDERER")
            self.device = why.split(";")[0]
            self.log(f"batch: {self.label} (pid {os.getpid()}) renders on {why}; GL renderer "
                     f"{self.gl_renderer}")
        elif threading.get_ident() != self._thread:
            raise RuntimeError(f"{self.label}: a GL context is bound to the thread that made it; "
                               "this worker was called from another thread")
        return self._ctx

    def renderer(self, key: str, scene: Scene):
        from shadowvol.raster.renderer import Renderer

        slot = (key, scene.width, scene.height)
        if slot in self._renderers:
            self._renderers.move_to_end(slot)
            return self._renderers[slot]
        ctx = self._context()
        while len(self._renderers) >= MAX_RENDERERS:
            self._renderers.popitem(last=False)[1].release()
        try:
            self._renderers[slot] = Renderer(scene, ctx)
        except SceneError as exc:  # the GL's limits (`image`, `objects`): name the scene file
            source = self.scenes.get(key)
            raise (exc.in_file(source) if isinstance(source, str) else exc) from None
        return self._renderers[slot]

    # -- frames ----------------------------------------------------------------------------
    def render(self, spec: dict) -> dict:
        """One frame: {"id", "outputs": {name: bytes}, "camera", "lights", "size", "seconds",
        "versions", "device"} or, when it fails, {"id", "error", "status"}."""
        start = time.perf_counter()
        try:
            scene, camera, lights = self._frame_scene(spec)
            loaded = time.perf_counter()
            dataset = None
            if "format" in spec:  # a dataset layout's files and index record (batch.formats)
                encoded, dataset = formats.frame(self, spec, scene, camera, lights)
            else:
                arrays = self._arrays(spec, scene, camera, lights)
            rendered = time.perf_counter()
            if dataset is None:
                encoded = {name: OUTPUTS[name].encode(arrays) for name in spec["outputs"]}
            done = time.perf_counter()
        except (KeyboardInterrupt, signals.Terminated):
            raise
        except Exception as exc:  # noqa: BLE001 - a bad frame is recorded, the others go on
            code = status_of(exc)
            text = message(exc) if code is not None else f"{type(exc).__name__}: {exc}"
            return {"id": spec["id"], "error": text,
                    "status": code if code is not None else RENDER_FAILED}
        return {"id": spec["id"], "outputs": encoded, "camera": camera_dict(camera),
                "lights": [light_dict(x) for x in lights], "size": [scene.width, scene.height],
                "seconds": {"scene": round(loaded - start, 6),
                            "render": round(rendered - loaded, 6),
                            "encode": round(done - rendered, 6)},
                "versions": self.versions(spec["renderer"]), "device": self.device,
                "worker": f"{self.label} (pid {os.getpid()})",
                **({"dataset": dataset} if dataset is not None else {})}

    def _frame_scene(self, spec: dict):
        scene = self.scene(spec["scene"])
        if spec["size"] is not None:
            scene = scene.replace(width=spec["size"][0], height=spec["size"][1])
        base = scene.camera
        camera = Camera(**{"up": base.up, "fov_y": base.fov_y, "near": base.near,
                           **spec["camera"]})
        lights = scene.lights if spec["lights"] is None else tuple(
            light_from_dict(x, f"lights[{i}]") for i, x in enumerate(spec["lights"]))
        camera, lights = frames.jittered(camera, lights, spec["jitter"], spec["seed"],
                                         spec["index"])
        return scene, camera, lights

    def _check_memory(self, spec, frame_scene: Scene, wanted, truth) -> None:
        """Refuse the frame (a SceneError naming its scene file and `image`, status 2) when
        its `memory` estimate exceeds this worker's budget: the one given, else `memory.ENV`,
        which a pool or Ray sets to the run's budget divided by its workers."""
        written = tuple(name for name, asks in (("png", "image" in wanted),
                                                ("masks", bool({"lit", "coverage"} & wanted)))
                        if asks)
        if spec["renderer"] == "raytrace":
            parts = [memory.whitted(frame_scene, written=())] if "image" in wanted else []
            if truth or {"lit", "coverage"} & wanted:
                parts.append(memory.ray_masks(frame_scene, truth, picture=False))
            estimate = memory.Estimate("the ray tracer", frame_scene.width, frame_scene.height,
                                       tuple(t for part in parts for t in part.terms))
        else:
            asked = tuple(name for name in wanted if name in RASTER_OUTPUTS)
            estimate = memory.raster(frame_scene, asked, written=written, gl_in_host=(
                self.gl_renderer is None or memory.gl_in_host(self.gl_renderer)))
        source = self.scenes.get(spec["scene"])
        memory.check(estimate, self.budget, source if isinstance(source, (str, os.PathLike))
                     else spec["scene"])

    def _arrays(self, spec, scene: Scene, camera: Camera, lights) -> dict[str, np.ndarray]:
        wanted = fields_of(spec["outputs"])
        truth = [name for name in GROUND_TRUTH if name in wanted]
        self._check_memory(spec, scene.replace(camera=camera, lights=lights), set(wanted),
                           truth)
        if spec["renderer"] == "raytrace":
            import raytrace

            frame_scene = scene.replace(camera=camera, lights=lights)
            arrays = {}
            if "image" in wanted:
                arrays["image"] = raytrace.render(frame_scene, max_depth=spec["max_depth"],
                                                  progress=False)
            soft = any(len(hard_lights(lt)) > 1 for lt in lights)
            if truth or (soft and {"lit", "coverage", "counts"} & set(wanted)):
                # the masks and an area light's counts come with it, on the same rays
                gt = raytrace.ground_truth(frame_scene, outputs=truth)
                arrays.update({name: getattr(gt, name) for name in truth},
                              lit=gt.lit, coverage=gt.coverage,
                              counts=soft_arrays(gt.lit_count, gt.samples))
            elif {"lit", "coverage", "counts"} & set(wanted):
                arrays["lit"], arrays["coverage"] = raytrace.shadow_masks(frame_scene)
                arrays["counts"] = {}
        else:
            renderer = self.renderer(spec["scene"], scene)
            asked = tuple(name for name in wanted if name in RASTER_OUTPUTS)
            if "counts" in wanted and "lit" not in asked:
                asked += ("lit",)
            result = renderer.render(spec["method"], camera=camera, lights=lights,
                                     outputs=asked)
            arrays = {name: getattr(result, name) for name in asked}
            if "counts" in wanted:   # what a mask file holds of an area light
                arrays["counts"] = soft_arrays(result.lit_count, result.samples)
        frame_scene = scene.replace(camera=camera, lights=lights)
        if "camera" in wanted:  # what every mask file holds beside the masks
            arrays["camera"] = calibration(frame_scene).arrays()
        if "light_samples" in wanted:
            arrays["light_samples"] = [light_samples(lt) for lt in lights]
        missing = [name for name in wanted if name not in arrays]
        if missing:
            raise ValueError(f"the {spec['renderer']} renderer does not make {missing[0]!r}")
        return arrays

    def versions(self, renderer: str) -> dict:
        out = {"shadowvol": __version__, "python": platform.python_version(),
               "numpy": np.__version__}
        if renderer == "raytrace":
            out["embreex"] = _version("embreex")
        else:
            out["moderngl"] = _version("moderngl")
            out["gl_renderer"] = self.gl_renderer
        return out

    def close(self) -> None:
        while self._renderers:
            self._renderers.popitem(last=False)[1].release()
        if self._ctx is not None:
            self._ctx.release()
            self._ctx = None
