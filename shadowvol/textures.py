"""Base-colour textures of the scene model: texels and their sampler (GL-free plain data).

The sampling rule both renderers follow is docs/CONVENTIONS.md, "Textures"; each renderer has
its own implementation of it (the rasterizer's in shaders/shade.frag, the ray tracer's in
`raytrace.texture`), so that the ray tracer stays an independent witness.  In short: UVs in
glTF's convention (u to the right, v down, (0, 0) the image's top-left corner); texel (i, j)
covers [i/w, (i+1)/w) x [j/h, (j+1)/h); every 8-bit sRGB texel decoded to linear, then filtered
(nearest, or bilinear between the four nearest texel centres; no mipmaps: level 0 always), the
wrap mode applied per texel index; times the material's diffuse colour (glTF's
baseColorFactor, OBJ's Kd) and the interpolated vertex colour.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shadowvol.checks import SceneError, frozen

WRAPS = ("repeat", "clamp", "mirror")   # glTF's REPEAT, CLAMP_TO_EDGE, MIRRORED_REPEAT
FILTERS = ("nearest", "linear")          # glTF's NEAREST, LINEAR (of the level-0 image)
# glTF sampler codes (the GL enums) -> the names above
GLTF_WRAPS = {10497: "repeat", 33071: "clamp", 33648: "mirror"}
GLTF_FILTERS = {9728: "nearest", 9729: "linear", 9984: "nearest", 9985: "linear",
                9986: "nearest", 9987: "linear"}
# the largest texture side accepted (the rasterizer reads texels from one storage buffer by
# int32 index, and the memory budget bounds the total: `shadowvol.memory`)
MAX_TEXTURE_SIDE = 1 << 15


@dataclass(frozen=True, eq=False)
class Texture:
    """A base-colour texture.

    texels : (h, w, 3) uint8, read-only: 8-bit sRGB codes, row 0 the image's top (v = 0)
    wrap_s, wrap_t : one of WRAPS, for u and v
    filter : one of FILTERS (glTF's magFilter, else the base filter of its minFilter, else
             linear), used at every distance: no mipmaps
    file   : the file the texels came from (an absolute path; "" for texels made in code):
             the image file, or with `image` the glTF/GLB file holding it
    image  : the index of the image in that glTF/GLB file's `images`, or None
    (`file` and `image` are what `save_scene` writes: the texture is read again from them)
    """

    texels: np.ndarray
    wrap_s: str = "repeat"
    wrap_t: str = "repeat"
    filter: str = "linear"
    file: str = ""
    image: int | None = None

    @property
    def source(self) -> str:
        """Where the texels came from, in words (for messages)."""
        if self.image is not None:
            return f"image {self.image} of {self.file}"
        return self.file or "a texture made in code"

    def __post_init__(self):
        t = np.asarray(self.texels)
        if t.dtype != np.uint8 or t.ndim != 3 or t.shape[2] != 3 or 0 in t.shape[:2]:
            raise SceneError("texture", f"expected (h, w, 3) uint8 texels, got {t.dtype} "
                                        f"{t.shape}")
        if max(t.shape[:2]) > MAX_TEXTURE_SIDE:
            raise SceneError("texture", f"{self.source or 'the texture'} is "
                                        f"{t.shape[1]}x{t.shape[0]}, more than "
                                        f"{MAX_TEXTURE_SIDE} texels a side")
        for key, value, allowed in (("wrap_s", self.wrap_s, WRAPS),
                                    ("wrap_t", self.wrap_t, WRAPS),
                                    ("filter", self.filter, FILTERS)):
            if value not in allowed:
                raise SceneError(f"texture.{key}", f"expected one of {', '.join(allowed)}, "
                                                   f"got {value!r}")
        object.__setattr__(self, "texels", frozen(np.ascontiguousarray(t)))

    @property
    def width(self) -> int:
        return int(self.texels.shape[1])

    @property
    def height(self) -> int:
        return int(self.texels.shape[0])

    @property
    def nbytes(self) -> int:
        return int(self.texels.nbytes)


def _floats(value, key: str) -> np.ndarray:
    try:
        return np.array(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise SceneError(key, "expected rows of numbers") from None


def vertex_uv(uv, n: int) -> np.ndarray | None:
    """(n, 2) float64 read-only UVs (glTF's convention), or None; a SceneError if malformed."""
    if uv is None:
        return None
    a = _floats(uv, "uv")
    if a.shape != (n, 2):
        raise SceneError("uv", f"expected ({n}, 2) texture coordinates, got shape {a.shape}")
    if not np.isfinite(a).all():
        raise SceneError("uv", "texture coordinates must be finite")
    return frozen(a)


def vertex_colours(colours, n: int) -> np.ndarray | None:
    """(n, 3) float64 read-only linear RGB vertex colours (>= 0), or None."""
    if colours is None:
        return None
    a = _floats(colours, "colors")
    if a.shape != (n, 3):
        raise SceneError("colors", f"expected ({n}, 3) vertex colours, got shape {a.shape}")
    if not np.isfinite(a).all() or (a < 0).any():
        raise SceneError("colors", "vertex colours must be finite and >= 0")
    return frozen(a)

