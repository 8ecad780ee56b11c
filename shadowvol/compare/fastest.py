"""Exact masks by the faster of the two renderers on this machine (issue 40, step 4): the
rasterizer's mask-only frame (`Renderer.render(outputs=("lit", "coverage"))`) or the ray
tracer's masks (`raytrace.shadow_masks`), chosen by a cost model (`choose`) when asked for
the masks alone (`shadowvol masks`, whose `--renderer` is `auto` unless told otherwise).

Both renderers give the float64 answer at every pixel that is not a tie (docs/CONVENTIONS.md,
"Which renderer makes the masks"); where a pixel is a tie their bits may differ, so the
choice, which depends on the machine, may change tie pixels and nothing else.  The choice is
deterministic: the same scene, GL renderer and Embree queries always choose the same.

The cost model (`costs`), in ms of one command (a scene loaded, its masks made once): on a
software GL (`shadowvol.memory.SOFTWARE_GL`, e.g. Mesa's llvmpipe) the rasterizer takes
RASTER_MS, RASTER_NS_PER_TRIANGLE per triangle (the Renderer built: geometry, topology), and
RASTER_NS_PER_TRIANGLE_LIGHT per triangle and RASTER_NS_PER_PIXEL_LIGHT per pixel for each
hard light (its volume pass); the ray tracer RAYS_NS_PER_TRIANGLE per triangle (the scene's
triangles and the BVH) and RAYS_NS_PER_RAY per ray with Embree's packets
(`raytrace.embree.PacketBackend`; SINGLE_RAYS_SLOWER times that with embreex's single rays),
a ray for each pixel and, from the SHADOW_RAY_SHARE of the pixels that are covered and face a
light, one per hard light (an area light's samples each count).  A process's first masks pay
once more: RASTER_FIRST_MS for the shaders, RAYS_FIRST_MS for the ray tracer's numba kernels
(the packets' and the masks' around them, `raytrace.maskkernels`, `raytrace.nearkernels`; the
single-ray path loads the last two as well) read from numba's cache.
The constants are the fit of `benchmarks.bench_fastest` at 7ea2da1 (after the masks' kernels
of issue 40 step 3; 13 scenes: 1k to 1M triangles, 77k to 920k pixels, 1 to 144 hard lights;
5 rounds, 2 cores, llvmpipe 256 bits, load 0.9-2.2), the run BENCHMARKS.md gives: on it the
model chose the faster renderer on 11 of 13, the worst 1.37x (the bunny: a scanned mesh's
many silhouette edges cost the rasterizer more than the model's icospheres); on a run just
before it (load 0.6-2.0, whose own fit gave RAYS_NS_PER_RAY 107: the soft scene's 26 M rays
weigh most) on 9 of 13, the worst 1.49x.  The first masks' costs are that run's (16 ms; 359
ms with packets, 338 ms with single rays: numba installed, the single rays asked for or
Embree's library not loadable; where numba is missing the single-ray path loads no kernels and
its first masks pay ~4 ms, which the model, keyed by the queries alone, overestimates).
SINGLE_RAYS_SLOWER is `benchmarks.bench_single_masks`' fit at 82cc7c0 (5 rounds, 1280x720,
load 0.6-0.7): whole masks, the Embree scene built each time, with single rays and with
packets; each scene's 1 + (single - packets) / (the model's rays at RAYS_NS_PER_RAY), the
median of 5 scenes 1.54 (10k 1.39, 100k 1.71 and 1.50 with 4 lights, the bunny 1.54; the
whole masks 1.61-1.96x the packets').  The 1M scene fits 7.1: the single rays' extra grows
with the BVH there (+640 ms over 666), which a per-ray constant cannot follow, so the model
underestimates the single rays on a million triangles.  (Before: 1.2, bench_packets' ratio of
the rays alone, from before the masks' kernels.)

The kernels' cache (`raytrace.packetkernels._jit`, numba's `cache=True`): numba keeps them in
$NUMBA_CACHE_DIR where that is set, else in the `__pycache__` beside the module where that is
writable, else in the user's cache directory (~/.cache/numba, or $XDG_CACHE_HOME/numba), so an
install into a read-only site-packages still caches them; an entry holds for the module's
source (its content hash) and the CPU.  RAYS_FIRST_MS assumes a warm cache, the usual case
from a machine's second command on: a fresh process's first masks at 32x24 took 360-375 ms
with it and 7,770-7,890 ms with an empty cache (the kernels compiled and written: the first
command after an install or upgrade, once).  Where no cache directory is writable at all numba
refuses `cache=True`, the kernels compile in every process (~7.8 s each), and the model, which
does not know, underestimates a one-shot command's ray tracer by that much.

A hardware GPU draws the rasterizer's frame, which the model does not time: there the
rasterizer is chosen.  Without a GL the ray tracer is; without Embree the rasterizer.

`shadowvol masks` chooses for its process's first masks (`first=True`); a batch job of
renderer "auto" (`shadowvol.batch.sources`) for each frame of a worker that renders many
(`first=False`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shadowvol.memory import gl_in_host
from shadowvol.scene import Scene, hard_lights

# what `--renderer` takes: the job file's names of the two renderers (docs/datasets.md), or auto
RENDERERS = ("auto", "shadowvol", "raytrace")
NAMES = {"shadowvol": "the rasterizer's mask-only frame", "raytrace": "the ray tracer"}

# the cost model (module docstring): benchmarks.bench_fastest's fit at 7ea2da1, 2026-12-05
RASTER_MS = 34.4
RASTER_NS_PER_TRIANGLE = 844.0
RASTER_NS_PER_TRIANGLE_LIGHT = 371.0
RASTER_NS_PER_PIXEL_LIGHT = 5.3
RAYS_NS_PER_TRIANGLE = 1399.0
RAYS_NS_PER_RAY = 71.0
SINGLE_RAYS_SLOWER = 1.54    # benchmarks.bench_single_masks: the median fit of 5 scenes
SHADOW_RAY_SHARE = 0.6       # the share of pixels sending a shadow ray: 0.50-0.62 measured
# a fresh process's first masks: the shaders compiled; the ray tracer's numba kernels loaded
RASTER_FIRST_MS = 16.0
RAYS_FIRST_MS = {"packets": 360.0, "single": 340.0}   # numba's cache warm


@dataclass(frozen=True)
class Choice:
    """Which renderer makes the masks, and why.  `renderer`: "shadowvol" or "raytrace";
    `asked`: what the user asked for (`RENDERERS`); `raster_ms`, `raytrace_ms`: the model's
    estimates (None where it did not estimate); `reason`: one line for the log."""

    renderer: str
    asked: str
    reason: str
    raster_ms: float | None = None
    raytrace_ms: float | None = None

    def describe(self) -> str:
        """"by the ray tracer (auto: ...)": what the command's log line says."""
        return f"by {NAMES[self.renderer]} ({self.asked}: {self.reason})"


def costs(triangles: int, pixels: int, lights: int, queries: str = "packets",
          first: bool = True) -> tuple[float, float]:
    """(rasterizer, ray tracer): the model's ms for the masks of `triangles` triangles,
    `pixels` pixels and `lights` hard lights (an area light's samples each count) on a
    software GL, the ray tracer with Embree's `queries` ("packets" or "single"); `first`:
    this process's first masks (a command's), which pay the one-off costs too."""
    raster = (RASTER_MS * 1e6 + RASTER_NS_PER_TRIANGLE * triangles
              + lights * (RASTER_NS_PER_TRIANGLE_LIGHT * triangles
                          + RASTER_NS_PER_PIXEL_LIGHT * pixels))
    per_ray = RAYS_NS_PER_RAY * (SINGLE_RAYS_SLOWER if queries == "single" else 1.0)
    rays = RAYS_NS_PER_TRIANGLE * triangles + per_ray * pixels * (1 + SHADOW_RAY_SHARE * lights)
    if first:
        raster += RASTER_FIRST_MS * 1e6
        rays += RAYS_FIRST_MS[queries] * 1e6
    return raster / 1e6, rays / 1e6


def choose(asked: str, triangles: int, pixels: int, lights: int, gl_renderer: str | None,
           queries: str | None, first: bool = True) -> Choice:
    """The renderer of a masks-only frame.  `asked`: one of `RENDERERS` (ValueError
    otherwise); `gl_renderer`: the GL's GL_RENDERER string, None where no GL context could be
    made; `queries`: Embree's queries here ("packets", "single"), None without Embree;
    `first`: as `costs` takes it.  A renderer asked for by name is that renderer."""
    if asked not in RENDERERS:
        raise ValueError(f"unknown renderer {asked!r} (one of: {', '.join(RENDERERS)})")
    if asked != "auto":
        return Choice(asked, asked, "asked for by name")
    if gl_renderer is None:
        return Choice("raytrace", asked, "no GL here")
    if queries is None:
        return Choice("shadowvol", asked, "no Embree here")
    if not gl_in_host(gl_renderer):
        return Choice("shadowvol", asked, f"a hardware GL ({gl_renderer})")
    raster, rays = costs(triangles, pixels, lights, queries, first)
    renderer = "raytrace" if rays < raster else "shadowvol"
    return Choice(renderer, asked, f"{triangles:,} triangles, {pixels:,} pixels, {lights} hard "
                                   f"lights on {gl_renderer.split(' (')[0]}: estimated "
                                   f"{raster:.0f} ms rasterized, {rays:.0f} ms ray traced "
                                   f"({queries} rays{', first masks' if first else ''})",
                  raster, rays)


def choose_for(scene: Scene, asked: str, gl_renderer: str | None, first: bool = True) -> Choice:
    """`choose` for `scene` on this machine: its sizes (`scene_sizes`) and Embree's queries
    (`ray_queries`) looked at only when `asked` is auto."""
    if asked != "auto":
        return choose(asked, 0, 0, 0, gl_renderer, None)
    return choose(asked, *scene_sizes(scene), gl_renderer, ray_queries(), first)


def scene_sizes(scene: Scene) -> tuple[int, int, int]:
    """(triangles, pixels, hard lights) of a scene, as `choose` takes them."""
    _, faces, _ = scene.triangles()
    lights = sum(len(hard_lights(light)) for light in scene.lights)
    return len(faces), scene.width * scene.height, lights


def ray_queries() -> str | None:
    """The Embree queries the ray tracer runs here ("packets" or "single"), None where
    embreex is missing (the ray tracer cannot run)."""
    from raytrace import embree4
    from raytrace.embree import embree_queries

    if embree4.embreex_module() is None:
        return None
    return embree_queries()


def masks(scene: Scene, renderer: str, ctx=None) -> tuple[np.ndarray, np.ndarray, dict]:
    """(lit, coverage, the mask file's other arrays) of `scene` by `renderer` ("shadowvol":
    on the GL context `ctx`; "raytrace"), as `shadowvol.frame.save_masks` writes them: the
    camera and light arrays and, with an area light, its counts."""
    if renderer == "shadowvol":
        from shadowvol.raster.renderer import Renderer

        with Renderer(scene, ctx) as r:
            result = r.render(outputs=("lit", "coverage"))
            return result.lit, result.coverage, result.arrays()
    if any(len(hard_lights(light)) > 1 for light in scene.lights):
        import raytrace

        truth = raytrace.ground_truth(scene, ())   # an area light's counts, on the same rays
        return truth.lit, truth.coverage, truth.arrays()
    import raytrace
    from shadowvol.cameras import calibration

    lit, coverage = raytrace.shadow_masks(scene)
    return lit, coverage, calibration(scene).arrays()
