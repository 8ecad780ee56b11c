"""How much memory an image needs, and the budget it must fit in.

`estimate(...)` is a model of the bytes one command allocates for its image, per renderer and
per output asked for: the sum of named terms, each "bytes per pixel x pixels" or a fixed tile
size, read off the code that allocates them (the arrays a call makes and keeps, its staging
buffers and its largest temporaries, and the encoders' copies).  It counts what grows with the
image; the process itself (Python, numpy, the GL driver, Embree, the scene's geometry) is the
fixed `BASE` allowance.  `tests/cli/test_memory_model.py` measures the peak RSS growth (VmHWM)
of fresh processes and checks the model is an upper bound within a factor of it.

`budget()` is the memory an image may take: `SHADOWVOL_MEMORY_BUDGET` (e.g. "12GiB"), or by
default 3/4 of the machine's memory (its physical memory, or the cgroup's limit when lower).
Not the memory free at the moment: that changes from one minute to the next, and a scene
should not be accepted once and refused the next time.  `check(...)` refuses an estimate over
the budget with a SceneError naming the file and the key `image` (exit status 2), before
anything big is allocated.

GL-free: the ray tracer imports it too.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

from shadowvol.fields import caster_words
from shadowvol.scene import Scene, SceneError, hard_lights

ENV = "SHADOWVOL_MEMORY_BUDGET"
DEFAULT_FRACTION = 0.75
# the process before the image: interpreter, numpy, Pillow, the GL driver's context and its
# compiled shaders, Embree's threads (measured: 110-200 MiB; kept apart from the image's terms)
BASE = 256 << 20

# shadowvol.raster.target.BYTES_PER_PIXEL (a test checks they agree): GL memory of a frame
GL_FRAME_BYTES_PER_PIXEL = 52
# renderers that keep their "GPU" memory in the process's own memory
SOFTWARE_GL = ("llvmpipe", "softpipe", "swrast", "lavapipe")

# rays traced together (raytrace.masks.MASK_TILE_RAYS, whitted.TILE_RAYS, pathtrace.TILE_PATHS;
# a test checks they agree) and the bytes one ray's tile arrays take at their peak (the hit
# records, the shading and shadow-ray arrays of a tile, a few dozen float64 values a ray):
# bounds from the measured growth less the per-pixel terms (100-400 B a ray; Whitted on
# scenes/whitted.toml at depth 5, glass and mirrors), rounded up
MASK_TILE_RAYS, WHITTED_TILE_RAYS, PATH_TILE_PATHS = 1 << 15, 1 << 15, 1 << 15
MASK_RAY_BYTES, WHITTED_RAY_BYTES, PATH_RAY_BYTES = 512, 1024, 512

# encoders (shadowvol.io), bytes per pixel of an RGB image: the sRGB bytes (3), Pillow's RGBX
# copy (4), the PNG bytes held twice (the stream and its value; at most the raw 3 + a little:
# deflate never grows data by more than 0.1%)
PNG = 3 + 4 + 2 * 3.01
PNG16 = 6 + 6 + 6 + 2 * 6.01     # pixels, rows, their bytes, the deflated stream twice
EXR = 12 + 12 + 2 * 12.01        # float32 copy, planar copy, blocks and their join
EXR64 = EXR + 12                 # a float64 image is first copied to float32


@dataclass(frozen=True)
class Estimate:
    """What one image needs: `terms`, (name, bytes) each, and their total."""

    what: str
    width: int
    height: int
    terms: tuple[tuple[str, int], ...]

    @property
    def total(self) -> int:
        return sum(b for _, b in self.terms)

    def describe(self) -> str:
        """The model in words: bytes per pixel of each term, biggest first."""
        px = self.width * self.height
        parts = sorted((t for t in self.terms if t[1]), key=lambda t: -t[1])
        text = ", ".join(f"{name} {size(b)}" if "tiles" in name else f"{name} {b / px:.0f} B/px"
                         for name, b in parts[:4])  # the tiles do not grow with the image
        return text + (f", {len(parts) - 4} more" if len(parts) > 4 else "")


def size(n: float) -> str:
    """12.3 GiB, 456 MiB, 78 KiB."""
    for unit, shift in (("GiB", 30), ("MiB", 20), ("KiB", 10)):
        if n >= 1 << shift:
            return f"{n / (1 << shift):.{1 if n < 10 << shift else 0}f} {unit}"
    return f"{int(n)} B"


def _terms(px: int, per_pixel: dict[str, float], fixed: dict[str, int] | None = None):
    out = [(name, int(math.ceil(b * px))) for name, b in per_pixel.items() if b]
    out += [(name, int(b)) for name, b in (fixed or {}).items() if b]
    return tuple(out)


def _tiles(width: int, tile_rays: int, ray_bytes: int, threads: int) -> int:
    """The tiles in flight: one per thread, each at least one row of the image."""
    return threads * max(tile_rays, width) * ray_bytes


def threads() -> int:
    """The ray tracer's threads: one per core this process may use."""
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
               else os.cpu_count() or 1)


def raster(scene: Scene, outputs=("image", "lit", "coverage"), *, gl_in_host: bool = True,
           written=("png",), stencil: bool = False, volumes: bool = False) -> Estimate:
    """`Renderer.render` of `scene` (shadowvol.raster) and the files `written` ("png",
    "exr", "png16", "masks", "stencil", "volumes").  `gl_in_host`: the GL keeps its frame in
    this process's memory (a software renderer, `SOFTWARE_GL`)."""
    L = len(scene.lights)
    samples = sum(len(hard_lights(lt)) for lt in scene.lights)
    pages = max(1, math.ceil(samples / 23))   # target.LIGHTS_PER_PAGE
    outputs = set(outputs)
    t = {"GL frame" + ("" if gl_in_host else " (GPU)"): GL_FRAME_BYTES_PER_PIXEL * gl_in_host,
         # target: RGBA and RGB float32, bits float32 and uint32 read-back staging, allocated
         # once
         "read-back staging": 16 + 12 + 4 + 4,
         "lit bits (uint32 per page)": 4 * pages,
         "coverage": (4 + 1) if "coverage" in outputs or "lit" in outputs else 0,
         "image float32": 12 if "image" in outputs else 0,
         # lit_count uint16 and lit bool per light, one bool mask and one uint32 temporary
         "lit_count + lit": (3 * L + 1 + 4) if "lit" in outputs else 0,
         "image_srgb": 6 if "image_srgb" in outputs else 0}
    truth = outputs & {"depth", "distance", "normal", "object_id", "facing", "facing_count",
                       "casters"}
    K = caster_words(len(scene.objects))
    if truth:
        # depth read (float32), its float64 quotient and the depth, the covered mask
        t["depth"] = 4 + 8 + 4 + 1
        if "distance" in truth:
            t["distance"] = 8 + 4 + 4      # ray lengths float64, the product, the float32
        if truth & {"normal", "object_id", "casters"}:
            # G-buffer read RGBA32F, the key int64 (where + astype), triangle, front, the
            # per-pixel triangle index, then normal float32 x3 and its float64 rows
            t["surface read"] = 16 + 8 + 8 + 8 + 1 + 8
            t["normal"] = (12 + 24) if "normal" in truth else 0
            t["object_id"] = (2 + 8) if "object_id" in truth else 0
        if truth & {"facing", "facing_count", "casters"}:
            # the counts (uint16) and their bools, a sample's unmasked bits
            t["facing + its lit"] = 2 * L + 2 * L + 2 * L + 8
        if "casters" in truth:
            t["casters"] = 8 * L * K + 16 * K   # the result, a sample's words and their OR
    if stencil:
        t["stencil counts"] = 4 * L + 4
    if volumes:
        # its frame's image, the RGBA read (a copy of the staging), its RGB copy
        t["volume view"] = 12 + 16 + 12
    t |= _written(written, L, truth, float64=False, stencil=stencil, words=K)
    return Estimate("the rasterizer", scene.width, scene.height,
                    _terms(scene.width * scene.height, t))


def _written(written, L: int, truth, float64: bool, stencil: bool = False, words: int = 1
             ) -> dict:
    """The encoders' bytes per pixel for the files written (the largest file at a time: files
    are written one after the other, each freed before the next)."""
    truth_bytes = {"depth": 4, "distance": 4, "normal": 12, "object_id": 2, "facing": L,
                   "facing_count": 2 * L, "casters": 8 * L * words}
    per = {"png": PNG, "png16": PNG16, "exr": EXR64 if float64 else EXR,
           # npz: the compressed stream twice (value and copy), at most the raw bytes
           "masks": 2 * 1.01 * (L + 1 + sum(truth_bytes[k] for k in truth)),
           # heat maps: an RGB panel per light, float64 colours, and its PNG
           "stencil": L * (3 + 24 + PNG) + 24 if stencil else 0,
           "volumes": PNG}
    largest = max((per[w] for w in written), default=0)
    return {"writing (" + ", ".join(written) + ")": largest} if written else {}


def ray_masks(scene: Scene, outputs=(), picture: bool = True, exact: int = 0) -> Estimate:
    """`raytrace.shadow_masks` / `ground_truth` / `soft_masks` of `scene` and `raytrace masks`
    writing them (the .npz and, with `picture`, its PNG); `exact`: how many of the float64
    (L, H, W) exact-visibility outputs (`raytrace.exact_soft`) come too."""
    L = len(scene.lights)
    truth = set(outputs)
    per = {"lit + coverage": L + 1,
           "ground truth": (4 * ("depth" in truth) + 4 * ("distance" in truth)
                            + 12 * ("normal" in truth) + 2 * ("object_id" in truth)
                            + L * ("facing" in truth) + 2 * L * ("facing_count" in truth)
                            + 8 * L * caster_words(len(scene.objects)) * ("casters" in truth)
                            + (L + 1) * bool(truth)),
           # soft lights: lit_count uint16 and facing per light
           "lit_count": 3 * L if any(len(hard_lights(lt)) > 1 for lt in scene.lights) else 0,
           # both computed at once (float64), those asked for written (npz: twice, compressed)
           "exact visibility": (16 + 2 * 1.01 * 8 * exact) * L if exact else 0,
           # one RGB uint8 panel per light (and per output), the joined picture, its PNG;
           # the outputs' heat maps colour one panel at a time in float64
           "picture": ((L + len(truth)) * 3 * 2 + 24 * bool(truth) + PNG) if picture else 0}
    per |= _written(("masks",), L, truth, float64=False, words=caster_words(len(scene.objects)))
    fixed = {"tiles in flight": _tiles(scene.width, MASK_TILE_RAYS, MASK_RAY_BYTES, threads())}
    return Estimate("the ray tracer's masks", scene.width, scene.height,
                    _terms(scene.width * scene.height, per, fixed))


def whitted(scene: Scene, written=("png",)) -> Estimate:
    """`raytrace.whitted.render` of `scene` ((H, W, 3) float64) and the files written."""
    per = {"image float64": 24} | _written(written, len(scene.lights), (), float64=True)
    fixed = {"tiles in flight": _tiles(scene.width, WHITTED_TILE_RAYS, WHITTED_RAY_BYTES,
                                       threads())}
    return Estimate("the Whitted ray tracer", scene.width, scene.height,
                    _terms(scene.width * scene.height, per, fixed))


def path_traced(scene: Scene, spp: int, written=("png",)) -> Estimate:
    """`raytrace.pathtrace.render`: the float64 sums and squares, then the mean, the variance
    and their temporaries (6 x 24 B/px at the end; one more as the margin measured: the
    tiles' results added into the sums), and the files written."""
    per = {"sums, mean, variance (float64)": 7 * 24} | \
        _written(written, len(scene.lights), (), float64=True)
    fixed = {"tiles in flight": threads() * max(PATH_TILE_PATHS, scene.width * spp)
             * PATH_RAY_BYTES}
    return Estimate("the path tracer", scene.width, scene.height,
                    _terms(scene.width * scene.height, per, fixed))


def radiosity_display(scene: Scene, written=("png",), flat: bool = False) -> Estimate:
    """`raytrace.radiosity.display`, untiled: every pixel's ray float64 (origin, direction,
    their unit copy), the hits, the image and the barycentric blend's per-pixel arrays; with
    `flat` the interpolated image is kept while the flat one is made."""
    per = {"rays (float64)": 3 * 24 + 8 + 8, "image float64": 24 * (1 + flat),
           # p, corners (3x3), e1, e2, q, 7 dot products, u v w, products, the mask arrays
           "barycentric blend": 24 + 72 + 72 + 72 + 56 + 24 + 72 + 32} | \
        _written(written, len(scene.lights), (), float64=True)
    return Estimate("the radiosity display", scene.width, scene.height,
                    _terms(scene.width * scene.height, per))


def compare(scene: Scene, gl_in_host: bool = True) -> Estimate:
    """`shadowvol compare` (`shadowvol.compare.comparison`): the rasterizer's frame and one
    float32 image per light (a list, then an array of them), the ray tracer's masks and one
    float64 Whitted image per light (the same), and the picture: per light a row of three
    uint8 panels (two sRGB encodings, the difference), the row, the joined rows, its PNG."""
    L = max(len(scene.lights), 1)
    px = scene.width * scene.height
    a = raster(scene, gl_in_host=gl_in_host, written=())
    b = ray_masks(scene, picture=False)
    tiles = max(_tiles(scene.width, MASK_TILE_RAYS, MASK_RAY_BYTES, threads()),
                _tiles(scene.width, WHITTED_TILE_RAYS, WHITTED_RAY_BYTES, threads()))
    per = {"raster image per light": 2 * 12 * L, "ray-traced image per light": 2 * 24 * L,
           "picture": L * (3 * 3 + 2 * 9 + 3 * PNG)}
    terms = (a.terms + tuple((f"ray tracer: {n}", v) for n, v in b.terms
                             if n.startswith("lit")) + _terms(px, per, {"tiles in flight": tiles}))
    return Estimate("shadowvol compare", scene.width, scene.height, terms)


# ---- the budget --------------------------------------------------------------------------------

_UNITS = {"": 1, "b": 1, "k": 1 << 10, "kb": 1000, "kib": 1 << 10, "m": 1 << 20, "mb": 10**6,
          "mib": 1 << 20, "g": 1 << 30, "gb": 10**9, "gib": 1 << 30, "t": 1 << 40,
          "tb": 10**12, "tib": 1 << 40}


def parse_size(text: str, key: str = ENV) -> int:
    """"12GiB", "12G" (binary), "12GB" (decimal), "500MiB", "1.5 GiB", "123456" bytes."""
    m = re.fullmatch(r"\s*(\d+(?:\.\d*)?|\.\d+)\s*([A-Za-z]*)\s*", str(text))
    unit = m and m[2].lower()
    if not m or unit not in _UNITS or float(m[1]) <= 0:
        raise SceneError(key, f"expected a memory size such as 12GiB, 500MiB or 2000000000 "
                              f"(bytes), got {text!r}")
    return int(float(m[1]) * _UNITS[unit])


def machine_memory() -> int:
    """The memory this process can have: physical memory, or a lower cgroup limit."""
    total = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    for limit in ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"):
        try:
            text = Path(limit).read_text().strip()
        except OSError:
            continue
        if text.isdigit():
            total = min(total, int(text))
    return total


def budget(value: int | str | None = None, key: str = "memory_budget") -> int:
    """The memory budget in bytes: `value` (bytes or a size such as "12GiB"; a bad one is a
    SceneError naming `key`), else $SHADOWVOL_MEMORY_BUDGET, else DEFAULT_FRACTION of
    `machine_memory()`."""
    if value is None:
        value, key = os.environ.get(ENV) or None, ENV
    if value is None:
        return int(DEFAULT_FRACTION * machine_memory())
    if isinstance(value, str):
        return parse_size(value, key)
    if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
        raise SceneError(key, f"must be a positive number of bytes, got {value!r}")
    return value


def check(estimate: Estimate, limit: int | str | None = None, file: str | None = None,
          key: str = "--memory-budget") -> None:
    """Raise SceneError (key `image`, naming `file`) when `estimate` exceeds the budget
    `limit` (a command's `key`, by default its --memory-budget)."""
    allowed = budget(limit, key)
    need = estimate.total + BASE
    if need > allowed:
        raise SceneError(
            "image", f"{estimate.width}x{estimate.height} needs about {size(need)} for "
                     f"{estimate.what} (model: {estimate.describe()}, + {size(BASE)} for the "
                     f"process), more than the memory budget of {size(allowed)} (set {ENV}, "
                     "e.g. 32GiB, or --memory-budget to change it)", file)


def gl_in_host(renderer_name: str) -> bool:
    """Whether a GL of this GL_RENDERER string keeps its frames in the process's memory (a
    software renderer, `SOFTWARE_GL`)."""
    return any(name in renderer_name.lower() for name in SOFTWARE_GL)
