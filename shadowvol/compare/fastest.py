"""Exact masks by the faster of the two renderers on this machine (issue 40, step 4): the
rasterizer's mask-only frame (`Renderer.render(outputs=("lit", "coverage"))`) or the ray
tracer's masks (`raytrace.shadow_masks`), chosen by a cost model (`choose`) when asked for
the masks alone (`shadowvol masks`, whose `--renderer` is `auto` unless told otherwise).

Both renderers give the float64 answer at every pixel that is not a tie (docs/CONVENTIONS.md,
"Which renderer makes the masks"); where a pixel is a tie their bits may differ, so the
choice, which depends on the machine, may change tie pixels and nothing else.  The choice is
deterministic: the same scene, GL renderer and Embree queries always choose the same.

The cost model, in ns (`costs`): a software GL (`shadowvol.memory.SOFTWARE_GL`, e.g. Mesa's
llvmpipe) draws a mask-only frame in about RASTER_NS_PER_TRIANGLE_LIGHT per triangle and hard
light plus RASTER_NS_PER_PIXEL_LIGHT per pixel and hard light (the volume pass of each light
over its triangles and the screen); the ray tracer builds its BVH in RAYS_NS_PER_TRIANGLE per
triangle and traces each pixel's primary ray and, from the SHADOW_RAY_SHARE of the pixels that
are covered and face a light, one shadow ray per hard light, RAYS_NS_PER_RAY each with
Embree's packets (`raytrace.embree.PacketBackend`), SINGLE_RAYS_SLOWER times that with
embreex's single rays.  The constants are the least-squares fit of the four scenes of
BENCHMARKS.md, "Exact masks against the peers" (`benchmarks.bench_peers` at d0150e1: 100k and
1M triangles at 1280x720 under one light, two bunnies under two, the turntable at 640x480
under three; 2 cores, llvmpipe 256 bits, wall ms); it chooses the faster one on each of them.
A hardware GPU draws the rasterizer's frame, which the model does not time: there the
rasterizer is chosen.  Without a GL the ray tracer is; without Embree the rasterizer.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shadowvol.memory import gl_in_host
from shadowvol.scene import Scene, hard_lights

# what `--renderer` takes: the job file's names of the two renderers (docs/formats.md), or auto
RENDERERS = ("auto", "shadowvol", "raytrace")
NAMES = {"shadowvol": "the rasterizer's mask-only frame", "raytrace": "the ray tracer"}

# the cost model (module docstring): ns, fitted to BENCHMARKS.md's four scenes
RASTER_NS_PER_TRIANGLE_LIGHT = 92.7
RASTER_NS_PER_PIXEL_LIGHT = 50.3
RAYS_NS_PER_TRIANGLE = 92.4
RAYS_NS_PER_RAY = 62.7
SINGLE_RAYS_SLOWER = 1.2     # benchmarks.bench_packets: single / packets 1.15-1.24x
SHADOW_RAY_SHARE = 0.6       # the share of pixels sending a shadow ray: 0.50-0.62 measured


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


def costs(triangles: int, pixels: int, lights: int, queries: str = "packets"
          ) -> tuple[float, float]:
    """(rasterizer, ray tracer): the model's ms of one mask frame of `triangles` triangles,
    `pixels` pixels and `lights` hard lights (an area light's samples each count) on a
    software GL, the ray tracer with Embree's `queries` ("packets" or "single")."""
    raster = lights * (RASTER_NS_PER_TRIANGLE_LIGHT * triangles
                       + RASTER_NS_PER_PIXEL_LIGHT * pixels)
    per_ray = RAYS_NS_PER_RAY * (SINGLE_RAYS_SLOWER if queries == "single" else 1.0)
    rays = RAYS_NS_PER_TRIANGLE * triangles + per_ray * pixels * (1 + SHADOW_RAY_SHARE * lights)
    return raster / 1e6, rays / 1e6


def choose(asked: str, triangles: int, pixels: int, lights: int, gl_renderer: str | None,
           queries: str | None) -> Choice:
    """The renderer of a masks-only frame.  `asked`: one of `RENDERERS` (ValueError
    otherwise); `gl_renderer`: the GL's GL_RENDERER string, None where no GL context could be
    made; `queries`: Embree's queries here ("packets", "single"), None without Embree.  A
    renderer asked for by name is that renderer."""
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
    raster, rays = costs(triangles, pixels, lights, queries)
    renderer = "raytrace" if rays < raster else "shadowvol"
    return Choice(renderer, asked, f"{triangles:,} triangles, {pixels:,} pixels, {lights} hard "
                                   f"lights on {gl_renderer.split(' (')[0]}: estimated "
                                   f"{raster:.0f} ms rasterized, {rays:.0f} ms ray traced "
                                   f"({queries} rays)", raster, rays)


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
