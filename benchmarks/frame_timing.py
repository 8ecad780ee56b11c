"""Timing shadowvol's frames, their phases, and pyrender's frames of the same scene.

Clocks
------
* Whole frames: wall time (`time.perf_counter`) of `Renderer.render(...)`, which returns only
  after reading the image and the lit masks back, so the GPU work is inside the clock; the
  plain frame (`plain`) likewise returns after its RGBA8 read-back.
* Phases: glFinish-bracketed wall time.  llvmpipe defers rasterization until a flush, so each
  phase is bracketed by `ctx.finish()` before and after (the functions the renderer calls are
  wrapped for one instrumented frame; the extra finishes make that frame a little slower than
  an uninstrumented one, so phases are reported from their own frames, not subtracted from the
  whole-frame medians).  GPU silhouettes run inside the volume pass (a geometry shader), so
  they are also timed alone: the edge records drawn with GL_RASTERIZER_DISCARD.
"""

from __future__ import annotations

import contextlib
import statistics
import time
import tracemalloc
from collections import defaultdict

import moderngl
import numpy as np

from shadowvol import Renderer
from shadowvol.raster import passes
from shadowvol.raster.volumes.silhouettes import (
    edge_multiplicity,
    quads_to_triangles,
    side_quads,
    topology_signs,
)

METHODS = ("zpass", "zfail", "auto")
SILHOUETTES = ("cpu", "gpu")


def stats(times_s: list[float]) -> dict:
    """{"median", "min", "max", "n"} in milliseconds."""
    ms = [t * 1e3 for t in times_s]
    return {"median": statistics.median(ms), "min": min(ms), "max": max(ms), "n": len(ms)}


def interleaved(fns: dict, repeat: int, warmup: int, alternate: bool = False,
                raw: dict | None = None) -> dict:
    """{name: stats} of each function, `warmup` untimed rounds then `repeat` timed ones; the
    functions take turns within each round, so load from other processes on the machine hurts
    all of them alike and their ratios stay meaningful.  `alternate`: every other round runs
    them in reverse order, so that no variant always follows the same one (what a variant
    leaves in the caches and in llvmpipe's state then weighs on both alike).  `raw`: a dict
    that receives each function's timed seconds, round by round (for paired statistics)."""
    times = defaultdict(list)
    for r in range(warmup + repeat):
        order = list(fns.items())
        for name, fn in (order[::-1] if alternate and r % 2 else order):
            t0 = time.perf_counter()
            fn()
            if r >= warmup:
                times[name].append(time.perf_counter() - t0)
    if raw is not None:
        raw.update(times)
    return {name: stats(ts) for name, ts in times.items()}


# ---------------------------------------------------------------------------------------------
# Phases
# ---------------------------------------------------------------------------------------------

PHASES = ("geometry pass", "silhouettes (CPU, incl. upload)", "volume pass", "mark unshadowed",
          "shading pass", "read-back")


@contextlib.contextmanager
def _phase_clock(renderer: Renderer, sink: dict):
    """Wrap the renderer's pass functions so that each call adds its glFinish-bracketed wall
    time to sink[phase]."""
    ctx = renderer.ctx
    undo = []

    def wrap(owner, name, phase, instance=False):
        original = getattr(owner, name)

        def timed(*args, **kwargs):
            ctx.finish()
            t0 = time.perf_counter()
            out = original(*args, **kwargs)
            ctx.finish()
            sink[phase] += time.perf_counter() - t0
            return out

        setattr(owner, name, timed)
        undo.append((owner, name, original, instance))

    wrap(passes, "geometry_pass", "geometry pass")
    wrap(passes, "mask_pass", "geometry pass")          # a mask-only frame's geometry pass
    wrap(passes, "count_signed", "volume pass")
    wrap(passes, "mark_unshadowed", "mark unshadowed")
    wrap(passes, "clear_shadowed", "mark unshadowed")   # a mask-only frame's per-light bits
    wrap(passes, "clear_shadowed_in_stencil", "mark unshadowed")   # ... kept in the stencil
    wrap(passes, "shade", "shading pass")
    for sil in SILHOUETTES:
        wrap(renderer.volumes(sil), "prepare",
             "silhouettes (CPU, incl. upload)" if sil == "cpu" else "_gpu prepare", True)
    for name in ("read_bits", "read_image", "read_unshadowed", "read_stencil_bits"):
        wrap(renderer.target, name, "read-back", True)
    try:
        yield
    finally:
        for owner, name, original, instance in reversed(undo):
            if instance:
                delattr(owner, name)      # back to the class's method
            else:
                setattr(owner, name, original)


@contextlib.contextmanager
def _gl_clock(sink: list):
    """Add to sink[0] the wall time spent inside GL calls that can wait for the GL (draws,
    which bin on the calling thread in llvmpipe; clears, reads and glFinish), moderngl's and
    the raw stencil and depth reads (`stencil`), while the block runs."""
    from shadowvol.raster import stencil
    undo = []

    def wrap(owner, name):
        original = getattr(owner, name)

        def timed(*args, **kwargs):
            t0 = time.perf_counter()
            try:
                return original(*args, **kwargs)
            finally:
                sink[0] += time.perf_counter() - t0

        setattr(owner, name, timed)
        undo.append((owner, name, original))

    for owner, names in ((moderngl.VertexArray, ("render",)),
                         (moderngl.Framebuffer, ("read_into", "read", "clear")),
                         (moderngl.Texture, ("read_into", "read")),
                         (moderngl.Context, ("finish", "clear")),
                         (stencil, ("read_stencil", "read_depth"))):
        for name in names:
            wrap(owner, name)
    try:
        yield
    finally:
        for owner, name, original in reversed(undo):
            setattr(owner, name, original)


def python_times(renderer: Renderer, repeat: int, **render_kw) -> dict:
    """{"frame": stats, "python": stats} over `repeat` frames (after two warm-up frames: a
    light's overflow bound is computed on its second frame, `Renderer._lights_to_check`): the
    whole frame, and its wall time outside the GL calls `_gl_clock` wraps: the Python (and
    numpy) work of a frame."""
    for _ in range(2):
        renderer.render(**render_kw)
    whole, python = [], []
    for _ in range(repeat):
        inside = [0.0]
        with _gl_clock(inside):
            t0 = time.perf_counter()
            renderer.render(**render_kw)
            t = time.perf_counter() - t0
        whole.append(t)
        python.append(t - inside[0])
    return {"frame": stats(whole), "python": stats(python)}


def phase_times(renderer: Renderer, method: str, silhouettes: str, repeat: int,
                **render_kw) -> dict:
    """{phase: stats} over `repeat` instrumented frames (after one warm-up frame), plus
    "instrumented frame" (the whole instrumented frame)."""
    renderer.render(method, silhouettes, **render_kw)
    runs = defaultdict(list)
    for _ in range(repeat):
        sink = defaultdict(float)
        with _phase_clock(renderer, sink):
            t0 = time.perf_counter()
            renderer.render(method, silhouettes, **render_kw)
            runs["instrumented frame"].append(time.perf_counter() - t0)
        for phase in PHASES:
            runs[phase].append(sink[phase])
    return {phase: stats(ts) for phase, ts in runs.items()}


def gpu_silhouette_times(renderer: Renderer, repeat: int, lights=None) -> dict:
    """The GPU silhouette geometry shader alone, for `lights` (default: the scene's): the
    edge records of all casters drawn with rasterizer discard, glFinish-bracketed."""
    ctx = renderer.ctx
    vols = renderer.volumes("gpu")
    from shadowvol.raster.platform.context import make_current
    from shadowvol.raster.projection import frame_view_projection
    make_current(ctx)
    scene = renderer.scene
    view_proj, origin = frame_view_projection(scene.camera, scene.size)
    renderer.geometry.move_to(origin)
    passes.set_camera(vols.programs, view_proj, scene.camera, origin)
    objects = [r.index for r in renderer.geometry.ranges]

    lights = scene.lights if lights is None else lights

    def run():
        for light in lights:
            light4 = light.homogeneous
            vols.prepare(light4)
            vols.draw_sides(objects)

    ctx.enable(moderngl.RASTERIZER_DISCARD)
    try:
        run()
        ctx.finish()
        times = []
        for _ in range(repeat):
            ctx.finish()
            t0 = time.perf_counter()
            run()
            ctx.finish()
            times.append(time.perf_counter() - t0)
    finally:
        ctx.disable(moderngl.RASTERIZER_DISCARD)
    return stats(times)


def cpu_silhouette_times(renderer: Renderer, repeat: int, lights=None) -> dict:
    """CPU silhouette extraction alone (signs, multiplicities, side quads as triangles; no
    upload, no cap lists) of all casters for `lights` (default: the scene's)."""
    topologies = renderer.geometry.topologies
    lights = [l.homogeneous for l in (renderer.scene.lights if lights is None else lights)]

    def run():
        for light4 in lights:
            for topo in topologies:
                signs = topology_signs(topo, light4)
                quads_to_triangles(side_quads(topo, edge_multiplicity(topo, signs), light4))

    run()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        run()
        times.append(time.perf_counter() - t0)
    return stats(times)


def python_peak_bytes(fn) -> int:
    """Peak of Python-heap allocations (tracemalloc: Python objects and numpy arrays; not the
    GL driver's memory) while `fn()` runs."""
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        fn()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


# ---------------------------------------------------------------------------------------------
# pyrender
# ---------------------------------------------------------------------------------------------

@contextlib.contextmanager
def pyrender_frames(scene):
    """Yields {"shadowed": fn, "unshadowed": fn}: pyrender 0.1.45 frames of `scene` (its own EGL
    context; each call makes it current and reads colour and depth back, as
    OffscreenRenderer.render always does).  The caller's context is current again after."""
    from shadowvol.compare import pyrender_peer

    pr_scene = pyrender_peer.to_pyrender(scene)
    with pyrender_peer._offscreen(scene.width, scene.height) as pr:
        shadowed, plain = pyrender_peer._flags(shadows=True), pyrender_peer._flags(shadows=False)
        yield {"shadowed": lambda: pr.render(pr_scene, flags=shadowed),
               "unshadowed": lambda: pr.render(pr_scene, flags=plain)}


def check_same_scene(renderer: Renderer) -> None:
    """A cheap sanity check that the frame we time draws something: coverage > 0."""
    result = renderer.render()
    if not result.coverage.any():
        raise RuntimeError("the benchmark scene covers no pixel")
    if not np.isfinite(result.image).all():
        raise RuntimeError("the benchmark frame has non-finite pixels")
