"""The scene's base-colour textures on the GPU, uploaded once per scene.

Every texture's texels go into ONE storage buffer (RGBA8 codes packed in a uint32 each, the
textures one after another: an atlas without packing), with a record per texture (first texel,
width, height, wrap and filter) and the 256-entry sRGB decoding table: shade.frag fetches the
texels by index and filters them itself (`base_colour` there), so that its rule is
docs/CONVENTIONS.md's, "Textures", bit for bit in its own float32: not GL's sampler, whose
bilinear weights are fixed-point on most GPUs and whose sRGB decoding is the driver's.  One
draw for all textures, whatever their sizes.
"""

from __future__ import annotations

import moderngl
import numpy as np

from shadowvol.errors import RenderError
from shadowvol.raster.glsl import set_uniform
from shadowvol.scene import Scene
from shadowvol.textures import WRAPS

# binding points of the storage buffers (the per-triangle data is 0: passes.shade)
TEXELS, RECORDS, DECODE = 1, 2, 3


def decode_table() -> np.ndarray:
    """(256,) float32: 8-bit sRGB code -> linear (IEC 61966-2-1), in float64 then rounded."""
    c = np.arange(256, dtype=np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).astype(np.float32)


def texture_index(scene: Scene) -> tuple[list, np.ndarray]:
    """The distinct textures of the scene's materials (each once, by identity) and each
    object's index among them (n_objects,) int32, -1 without a texture."""
    textures, where = [], {}
    index = np.full(len(scene.objects), -1, np.int32)
    for i, o in enumerate(scene.objects):
        t = o.material.texture
        if t is not None:
            if id(t) not in where:
                where[id(t)] = len(textures)
                textures.append(t)
            index[i] = where[id(t)]
    return textures, index


class SceneTextures:
    """The storage buffers of `textures` (a list of `shadowvol.textures.Texture`).  Call
    `release()`.  `nbytes`: what they take on the GPU."""

    def __init__(self, ctx: moderngl.Context, textures: list):
        texels = sum(t.width * t.height for t in textures)
        limit = ctx.info.get("GL_MAX_SHADER_STORAGE_BLOCK_SIZE", 1 << 27)
        if 4 * texels > limit:
            raise RenderError(f"the scene's textures hold {texels:,} texels; this GL reads at "
                              f"most {limit // 4:,} from one storage buffer")
        records = np.zeros((max(len(textures), 1), 4), np.int32)
        self.texels = ctx.buffer(reserve=max(4 * texels, 4))
        first = 0
        for k, t in enumerate(textures):
            rgba = np.empty((t.height, t.width, 4), np.uint8)
            rgba[..., :3], rgba[..., 3] = t.texels, 255
            self.texels.write(rgba.view(np.uint32).tobytes(), offset=4 * first)
            flags = (WRAPS.index(t.wrap_s) | WRAPS.index(t.wrap_t) << 2
                     | (t.filter == "linear") << 4)
            records[k] = first, t.width, t.height, flags
            first += t.width * t.height
        self.records = ctx.buffer(records.tobytes())
        self.decode = ctx.buffer(decode_table().tobytes())
        self.nbytes = 4 * texels + records.nbytes + 1024

    def bind(self, prog: moderngl.Program, target) -> None:
        """The shading pass's base-colour inputs (shade.frag's SURFACE): the G-buffer's UVs
        and vertex colours of `target` (a `target.Target`), the texels and their records."""
        target.uv.use(3)
        target.tint.use(4)
        set_uniform(prog, "u_uv", 3)
        set_uniform(prog, "u_tint", 4)
        self.texels.bind_to_storage_buffer(TEXELS)
        self.records.bind_to_storage_buffer(RECORDS)
        self.decode.bind_to_storage_buffer(DECODE)

    def release(self) -> None:
        for buf in (self.texels, self.records, self.decode):
            buf.release()
