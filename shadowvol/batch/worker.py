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

import contextlib
import dataclasses
import os
import platform
import sys
import threading
import time
from collections import OrderedDict

import numpy as np

from shadowvol import __version__, memory, signals
from shadowvol.batch import egl, jitter, job_frames, layouts
from shadowvol.batch.outputs import fields_of
from shadowvol.batch.sources import SOURCES
from shadowvol.batch.spec import FrameSpec
from shadowvol.cameras import calibration
from shadowvol.errors import RENDER_FAILED, message, status_of
from shadowvol.frame import GROUND_TRUTH
from shadowvol.scene import Camera, Scene, SceneError, light_samples
from shadowvol.scenefile import light_from_dict, load_scene

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


def light_dict(light) -> dict:
    """A light as plain data in the scene-file schema (for the manifest): its type and fields."""
    kind = type(light).__name__.removesuffix("Light").lower()
    out = {"type": kind}
    for f in dataclasses.fields(light):
        value = getattr(light, f.name)
        out[f.name] = value.tolist() if isinstance(value, np.ndarray) else value
    return out


def camera_dict(camera: Camera) -> dict:
    """A frame's camera for the manifest: eye, target, up, fov_y, near, and a matrix camera's
    intrinsics and pose as given (fov_y None)."""
    out = {"eye": camera.eye.tolist(), "target": camera.target.tolist(),
           "up": camera.up.tolist(), "fov_y": camera.fov_y, "near": camera.near}
    if camera.matrix_form:
        out.update(fx=camera.fx, fy=camera.fy, cx=camera.cx, cy=camera.cy,
                   camera_to_world=camera.camera_to_world.tolist())
    return out


def objects_dict(scene: Scene, jitter_spec: dict) -> list[dict]:
    """A jittered frame's objects for the manifest: name, category, pose (model to world, None
    for the identity) and, with colour jitter, the diffuse colour."""
    return [{"name": obj.name, "category": obj.label,
             "pose": None if obj.pose is None else obj.pose.tolist(),
             **({"diffuse": obj.material.diffuse.tolist()} if "colors" in jitter_spec else {})}
            for obj in scene.objects]


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
        self.masks_by = None     # the renderer of the last frame of renderer "auto"
        # (objects, frame origin, raytrace.masks.MaskTracer) of the last ray-traced frame:
        # the next frame with the same objects and eye reuses it (`batch.sources`)
        self.mask_tracer = None

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

    def context(self):
        from shadowvol.raster.platform.context import check_not_forked, create_context

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
            if self._renderers[slot].scene.objects is scene.objects:
                self._renderers.move_to_end(slot)
                return self._renderers[slot]
            self._renderers.pop(slot).release()   # a frame's jittered objects: new geometry
        ctx = self.context()
        while len(self._renderers) >= MAX_RENDERERS:
            self._renderers.popitem(last=False)[1].release()
        with self.naming(key):
            self._renderers[slot] = Renderer(scene, ctx)
        return self._renderers[slot]

    @contextlib.contextmanager
    def naming(self, key: str):
        """A Renderer(scene) refused inside (the GL's limits, `image` or `objects`) names the
        scene file of `key`, as a scene's other bad input does."""
        try:
            yield
        except SceneError as exc:
            source = self.scenes.get(key)
            raise (exc.in_file(source) if isinstance(source, str) else exc) from None

    # -- frames ----------------------------------------------------------------------------
    def render(self, spec: FrameSpec) -> dict:
        """One frame: {"id", "encoded": {name or path: bytes}, "camera", "lights", "size",
        "seconds", "versions", "device"} or, when it fails, {"id", "error", "status"}."""
        start = time.perf_counter()
        try:
            scene, camera, lights = self._frame_scene(spec)
            loaded = time.perf_counter()
            layout = layouts.of_spec(spec)   # the job's outputs, or a dataset's files
            arrays = layout.arrays(self, spec, scene, camera, lights)
            rendered = time.perf_counter()
            encoded, dataset = layout.encode(spec, arrays,
                                             scene.replace(camera=camera, lights=lights))
            done = time.perf_counter()
        except (KeyboardInterrupt, signals.Terminated):
            raise
        except Exception as exc:  # noqa: BLE001 - a bad frame is recorded, the others go on
            code = status_of(exc)
            text = message(exc) if code is not None else f"{type(exc).__name__}: {exc}"
            return {"id": spec.id, "error": text,
                    "status": code if code is not None else RENDER_FAILED}
        return {"id": spec.id, "encoded": encoded, "camera": camera_dict(camera),
                "lights": [light_dict(x) for x in lights], "size": [scene.width, scene.height],
                "seconds": {"scene": round(loaded - start, 6),
                            "render": round(rendered - loaded, 6),
                            "encode": round(done - rendered, 6)},
                "versions": self.versions(spec.renderer), "device": self.device,
                "worker": f"{self.label} (pid {os.getpid()})",
                **({"objects": objects_dict(scene, spec.jitter)}
                   if jitter.applies(spec.jitter) else {}),
                **({"dataset": dataset} if dataset is not None else {})}

    def _frame_scene(self, spec: FrameSpec):
        scene = self.scene(spec.scene)
        if spec.size is not None:
            scene = scene.replace(width=spec.size[0], height=spec.size[1])
        base = scene.camera
        if "camera_to_world" in spec.camera:   # intrinsics and pose: the job's own
            camera = Camera(**{"near": base.near, **spec.camera})
        else:
            camera = Camera(**{"up": base.up, "fov_y": base.fov_y, "near": base.near,
                               **spec.camera})
        lights = scene.lights if spec.lights is None else tuple(
            light_from_dict(x, f"lights[{i}]") for i, x in enumerate(spec.lights))
        camera, lights = job_frames.jittered(camera, lights, spec.jitter, spec.seed,
                                         spec.index)
        scene = jitter.jittered_scene(scene, spec.jitter, spec.seed, spec.index)
        return scene, camera, lights

    def _check_memory(self, spec, source, frame_scene: Scene, wanted, truth) -> None:
        """Refuse the frame (a SceneError naming its scene file and `image`, status 2) when
        its `memory` estimate exceeds this worker's budget: the one given, else `memory.ENV`,
        which a pool or Ray sets to the run's budget divided by its workers."""
        written = tuple(name for name, asks in (("png", "image" in wanted),
                                                ("masks", bool({"lit", "coverage"} & wanted)))
                        if asks)
        estimate = source.estimate(self, frame_scene, wanted, truth, written)
        where = self.scenes.get(spec.scene)
        memory.check(estimate, self.budget, where if isinstance(where, (str, os.PathLike))
                     else spec.scene)

    def arrays(self, spec, scene: Scene, camera: Camera, lights) -> dict[str, np.ndarray]:
        """The frame arrays its outputs need (`outputs.fields_of`), by its renderer's
        `sources.FrameSource`."""
        wanted = fields_of(spec.outputs)
        truth = [name for name in GROUND_TRUTH if name in wanted]
        source = SOURCES[spec.renderer]
        frame_scene = scene.replace(camera=camera, lights=lights)
        self._check_memory(spec, source, frame_scene, set(wanted), truth)
        arrays = source.arrays(self, spec, scene, camera, lights, wanted, truth)
        if "camera" in wanted:  # what every mask file holds beside the masks
            arrays["camera"] = calibration(frame_scene).arrays()
        if "light_samples" in wanted:
            arrays["light_samples"] = [light_samples(lt) for lt in lights]
        missing = [name for name in wanted if name not in arrays]
        if missing:
            raise ValueError(f"the {spec.renderer} renderer does not make {missing[0]!r}")
        return arrays

    def versions(self, renderer: str) -> dict:
        return {"shadowvol": __version__, "python": platform.python_version(),
                "numpy": np.__version__, **SOURCES[renderer].versions(self)}

    def close(self) -> None:
        while self._renderers:
            self._renderers.popitem(last=False)[1].release()
        if self._ctx is not None:
            self._ctx.release()
            self._ctx = None
