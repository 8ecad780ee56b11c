"""The memory the outlook's renderers take for an image (`shadowvol.memory`), from their own
tiles (`whitted.TILE_RAYS`, `path.pathtrace.TILE_PATHS`)."""

from __future__ import annotations

from shadowvol import memory
from shadowvol.scene import Scene

from .path.pathtrace import TILE_PATHS
from .whitted import TILE_RAYS

# the bytes one ray's (or path's) tile arrays take at their peak (the hit records, the shading
# and shadow-ray arrays of a tile, a few dozen float64 values a ray): bounds from the measured
# growth less the per-pixel terms (100-400 B a ray; Whitted on scenes/whitted.toml at depth 5,
# glass and mirrors), rounded up
WHITTED_RAY_BYTES, PATH_RAY_BYTES = 1024, 512


def whitted_tiles(width: int) -> int:
    """Whitted's tiles in flight: one per thread, each at least one row of the image."""
    return memory.tiles(width, TILE_RAYS, WHITTED_RAY_BYTES, memory.threads())


def whitted(scene: Scene, written=("png",)) -> memory.Estimate:
    """`raytrace.outlook.whitted.render` of `scene` ((H, W, 3) float64) and the files
    written."""
    per = {"image float64": 24} | memory.written(written, len(scene.lights), (), float64=True)
    fixed = {"tiles in flight": whitted_tiles(scene.width),
             # the model's sRGB codes and the ray tracer's float64 linear copy (`texture`)
             "textures": memory.texels(scene) * (3 + 24)}
    return memory.Estimate("the Whitted ray tracer", scene.width, scene.height,
                           memory.terms(scene.width * scene.height, per, fixed))


def layers(scene: Scene) -> memory.Estimate:
    """`raytrace.outlook.layers.layers` beyond its float32 outputs (which the masks' estimate
    counts, `shadowvol.memory.field_bytes`): one tile of `TILE_RAYS` rays at a time, Whitted's
    tile arrays and the per-light float64 sums (direct and shadowed, 48 B a light), and the
    textures' float64 copy."""
    rays = min(TILE_RAYS, max(scene.width, 1) * max(scene.height, 1))
    rays = max(rays, scene.width)
    fixed = {"a tile": rays * (WHITTED_RAY_BYTES + 48 * len(scene.lights)),
             "textures": memory.texels(scene) * (3 + 24)}
    return memory.Estimate("the ray tracer's layers", scene.width, scene.height,
                           memory.terms(scene.width * scene.height, {}, fixed))


def path_traced(scene: Scene, spp: int, written=("png",)) -> memory.Estimate:
    """`raytrace.outlook.path.pathtrace.render`: the float64 sums and squares, then the mean,
    the variance and their temporaries (6 x 24 B/px at the end; one more as the margin
    measured: the tiles' results added into the sums), and the files written."""
    per = {"sums, mean, variance (float64)": 7 * 24} | \
        memory.written(written, len(scene.lights), (), float64=True)
    fixed = {"tiles in flight": memory.threads() * max(TILE_PATHS, scene.width * spp)
             * PATH_RAY_BYTES, "textures": memory.texels(scene) * (3 + 24)}
    return memory.Estimate("the path tracer", scene.width, scene.height,
                           memory.terms(scene.width * scene.height, per, fixed))


def radiosity_display(scene: Scene, written=("png",), flat: bool = False) -> memory.Estimate:
    """`raytrace.outlook.radiosity.display`, untiled: every pixel's ray float64 (origin,
    direction, their unit copy), the hits, the image and the barycentric blend's per-pixel
    arrays; with `flat` the interpolated image is kept while the flat one is made."""
    per = {"rays (float64)": 3 * 24 + 8 + 8, "image float64": 24 * (1 + flat),
           # p, corners (3x3), e1, e2, q, 7 dot products, u v w, products, the mask arrays
           "barycentric blend": 24 + 72 + 72 + 72 + 56 + 24 + 72 + 32} | \
        memory.written(written, len(scene.lights), (), float64=True)
    return memory.Estimate("the radiosity display", scene.width, scene.height,
                           memory.terms(scene.width * scene.height, per))
