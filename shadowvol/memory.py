"""How much memory an image needs, and the budget it must fit in.

An `Estimate` is a model of the bytes one command allocates for its image, per renderer and
per output asked for, given by the renderer that allocates them (`shadowvol.raster.estimate`,
`raytrace.estimate`, `raytrace.outlook.estimate`; `shadowvol.compare.estimate` adds two up),
from the renderers' own numbers, never copies of them: the sum of named terms, each "bytes
per pixel x pixels" or a fixed tile size, read off the code that allocates them (the arrays a
call makes and keeps, its staging buffers and its largest temporaries, and the encoders'
copies).  It counts what grows with the
image; the process itself (Python, numpy, the GL driver, Embree, the scene's geometry) is the
fixed `BASE` allowance.  `tests/scene/test_memory_model.py` measures the peak RSS growth (VmHWM)
of fresh processes and checks the model is an upper bound within a factor of it.

`budget()` is the memory an image may take: `SHADOWVOL_MEMORY_BUDGET` (e.g. "12GiB"), or by
default 3/4 of the machine's memory (its physical memory, or the cgroup's limit when lower).
Not the memory free at the moment: that changes from one minute to the next, and a scene
should not be accepted once and refused the next time.  `check(...)` refuses an estimate over
the budget with a SceneError naming the file and the key `image` (exit status 2), before
anything big is allocated.

Here: the vocabulary (`Estimate`, `terms`, `tiles`, `threads`), the encoders' bytes (`written`,
of the frame's fields as `shadowvol.frame.FIELDS` declares them) and the budget.  GL-free: the
ray tracer imports it too.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from shadowvol.errors import InputError
from shadowvol.frame import FIELDS
from shadowvol.scene import Scene, SceneError

ENV = "SHADOWVOL_MEMORY_BUDGET"
DEFAULT_FRACTION = 0.75
# the process before the image: interpreter, numpy, Pillow, the GL driver's context and its
# compiled shaders, Embree's threads, and with Embree's packets numba, llvmlite and the compiled
# kernels (measured, VmHWM after a 16x12 `shadowvol compare` of scenes/stack.toml: 213 MiB with
# single rays, 314 MiB with the packets; kept apart from the image's terms)
BASE = 384 << 20

# renderers that keep their "GPU" memory in the process's own memory
SOFTWARE_GL = ("llvmpipe", "softpipe", "swrast", "lavapipe")

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


def terms(px: int, per_pixel: dict[str, float], fixed: dict[str, int] | None = None
          ) -> tuple[tuple[str, int], ...]:
    """(name, bytes) of each term: `per_pixel` bytes a pixel times `px` pixels (rounded up),
    and the `fixed` bytes; terms of 0 bytes are left out."""
    out = [(name, int(math.ceil(b * px))) for name, b in per_pixel.items() if b]
    out += [(name, int(b)) for name, b in (fixed or {}).items() if b]
    return tuple(out)


def tiles(width: int, tile_rays: int, ray_bytes: int, threads: int) -> int:
    """The tiles in flight: one per thread, each at least one row of the image."""
    return threads * max(tile_rays, width) * ray_bytes


def threads() -> int:
    """The ray tracer's threads: one per core this process may use."""
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
               else os.cpu_count() or 1)


def field_bytes(name: str, lights: int, words: int = 1) -> int:
    """Bytes a pixel of frame field `name` (`shadowvol.frame.FIELDS`) in a frame of `lights`
    lights and `words` caster words: its dtype's size times its dimensions other than H, W."""
    field = FIELDS[name]
    n = np.dtype(field.dtype).itemsize
    for dim in field.dims:
        n *= {"L": lights, "K": words, "H": 1, "W": 1}.get(dim, dim)
    return n


def texels(scene: Scene) -> int:
    """How many texels the scene's textures hold (each texture once)."""
    seen = {id(o.material.texture): o.material.texture for o in scene.objects
            if o.material.texture is not None}
    return sum(t.width * t.height for t in seen.values())


def surfaced(scene: Scene) -> bool:
    """Whether some object has a texture or vertex colours."""
    return any(o.material.texture is not None or o.colors is not None for o in scene.objects)


def written(files, L: int, truth, float64: bool, stencil: bool = False, words: int = 1
            ) -> dict:
    """The encoders' bytes per pixel for the `files` written ("png", "png16", "exr", "masks"
    with the ground truth `truth`, "stencil", "volumes": the largest file at a time: files are
    written one after the other, each freed before the next)."""
    per = {"png": PNG, "png16": PNG16, "exr": EXR64 if float64 else EXR,
           # npz: the compressed stream twice (value and copy), at most the raw bytes
           "masks": 2 * 1.01 * (L + 1 + sum(field_bytes(k, L, words) for k in truth)),
           # heat maps: an RGB panel per light, float64 colours, and its PNG
           "stencil": L * (3 + 24 + PNG) + 24 if stencil else 0,
           "volumes": PNG}
    largest = max((per[w] for w in files), default=0)
    return {"writing (" + ", ".join(files) + ")": largest} if files else {}


# ---- the budget --------------------------------------------------------------------------------

_UNITS = {"": 1, "b": 1, "k": 1 << 10, "kb": 1000, "kib": 1 << 10, "m": 1 << 20, "mb": 10**6,
          "mib": 1 << 20, "g": 1 << 30, "gb": 10**9, "gib": 1 << 30, "t": 1 << 40,
          "tb": 10**12, "tib": 1 << 40}


def parse_size(text: str, key: str = ENV) -> int:
    """"12GiB", "12G" (binary), "12GB" (decimal), "500MiB", "1.5 GiB", "123456" bytes."""
    m = re.fullmatch(r"\s*(\d+(?:\.\d*)?|\.\d+)\s*([A-Za-z]*)\s*", str(text))
    unit = m and m[2].lower()
    if not m or unit not in _UNITS or float(m[1]) <= 0:
        raise InputError(key, f"expected a memory size such as 12GiB, 500MiB or 2000000000 "
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
    """The memory budget in bytes: `value` (bytes or a size such as "12GiB"; a bad one is an
    InputError naming `key`), else $SHADOWVOL_MEMORY_BUDGET, else DEFAULT_FRACTION of
    `machine_memory()`."""
    if value is None:
        value, key = os.environ.get(ENV) or None, ENV
    if value is None:
        return int(DEFAULT_FRACTION * machine_memory())
    if isinstance(value, str):
        return parse_size(value, key)
    if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
        raise InputError(key, f"must be a positive number of bytes, got {value!r}")
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
