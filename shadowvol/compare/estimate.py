"""The memory `shadowvol compare` takes (`shadowvol.memory`): each renderer's own estimate
(`shadowvol.raster.estimate`, `raytrace.estimate`, `raytrace.outlook.estimate`) and the
comparison's images and picture."""

from __future__ import annotations

import raytrace.estimate
import raytrace.outlook.estimate
import shadowvol.raster.estimate
from shadowvol import memory
from shadowvol.scene import Scene


def compare(scene: Scene, gl_in_host: bool = True) -> memory.Estimate:
    """`shadowvol compare` (`shadowvol.compare.comparison`): the rasterizer's frame and one
    float32 image per light (a list, then an array of them), the ray tracer's masks and one
    float64 Whitted image per light (the same), and the picture: per light a row of three
    uint8 panels (two sRGB encodings, the difference), the row, the joined rows, its PNG."""
    L = max(len(scene.lights), 1)
    px = scene.width * scene.height
    a = shadowvol.raster.estimate.render(scene, gl_in_host=gl_in_host, written=())
    b = raytrace.estimate.masks(scene, picture=False)
    tiles = max(raytrace.estimate.tiles_in_flight(scene.width),
                raytrace.outlook.estimate.whitted_tiles(scene.width))
    per = {"raster image per light": 2 * 12 * L, "ray-traced image per light": 2 * 24 * L,
           "picture": L * (3 * 3 + 2 * 9 + 3 * memory.PNG)}
    terms = (a.terms + tuple((f"ray tracer: {n}", v) for n, v in b.terms
                             if n.startswith("lit"))
             + memory.terms(px, per, {"tiles in flight": tiles}))
    return memory.Estimate("shadowvol compare", scene.width, scene.height, terms)
