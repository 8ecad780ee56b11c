"""The base colour at ray hits: textures and vertex colours, in float64 (numpy).

The ray tracer's own implementation of docs/CONVENTIONS.md, "Textures" (the rasterizer has its
own, in shaders/shade.frag): the hit's barycentrics in float64 against the triangle's float64
world corners interpolate the vertices' UVs and colours; the texture is sampled there, each
texel decoded from 8-bit sRGB to linear first, then filtered (nearest or bilinear, level 0),
texel indices wrapped per axis.  The base colour multiplies the material's ambient and diffuse
colours; where an object has neither texture nor vertex colours it is 1.
"""

from __future__ import annotations

import numpy as np

from shadowvol.scene import Scene


def srgb_decode(codes) -> np.ndarray:
    """float64 linear values of 8-bit sRGB codes (IEC 61966-2-1), any shape."""
    c = np.asarray(codes, np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def wrap(i: np.ndarray, n: int, mode: str) -> np.ndarray:
    """Texel indices i (any shape, int64) wrapped into 0..n-1 by `mode` (`textures.WRAPS`)."""
    if mode == "repeat":
        return np.mod(i, n)
    if mode == "clamp":
        return np.clip(i, 0, n - 1)
    k = np.mod(i, 2 * n)   # mirror: 0..n-1, then n-1..0
    return np.where(k < n, k, 2 * n - 1 - k)


def sample(texture, linear: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(k, 3) float64: `texture` (a `shadowvol.textures.Texture`, its texels decoded to
    `linear` (h, w, 3) float64) at uv (k, 2) float64, by its filter and wrap modes."""
    h, w = linear.shape[:2]
    x, y = uv[:, 0] * w, uv[:, 1] * h

    def texel(i, j):
        return linear[wrap(j, h, texture.wrap_t), wrap(i, w, texture.wrap_s)]

    if texture.filter == "nearest":
        return texel(np.floor(x).astype(np.int64), np.floor(y).astype(np.int64))
    x, y = x - 0.5, y - 0.5          # texel centres at whole numbers
    fx, fy = np.floor(x), np.floor(y)
    i, j = fx.astype(np.int64), fy.astype(np.int64)
    ax, ay = (x - fx)[:, None], (y - fy)[:, None]
    top = texel(i, j) * (1.0 - ax) + texel(i + 1, j) * ax
    bottom = texel(i, j + 1) * (1.0 - ax) + texel(i + 1, j + 1) * ax
    return top * (1.0 - ay) + bottom * ay


def barycentrics(corners: np.ndarray, p: np.ndarray) -> np.ndarray:
    """(k, 3) float64 barycentric weights of points p (k, 3) in triangles corners (k, 3, 3)
    (the point projected into the triangle's plane)."""
    a = corners[:, 0]
    e1, e2, q = corners[:, 1] - a, corners[:, 2] - a, p - a
    d11, d12, d22 = (e1 * e1).sum(1), (e1 * e2).sum(1), (e2 * e2).sum(1)
    dq1, dq2 = (q * e1).sum(1), (q * e2).sum(1)
    den = d11 * d22 - d12 * d12
    den = np.where(den == 0.0, 1.0, den)   # a degenerate triangle: its first corner
    b1 = (d22 * dq1 - d12 * dq2) / den
    b2 = (d11 * dq2 - d12 * dq1) / den
    return np.stack([1.0 - b1 - b2, b1, b2], axis=1)


class SurfaceColours:
    """The base colour of a scene's objects at hit points (None from `of` when no object has
    a texture or vertex colours).

    colour(obj, face, p) : obj (k,) object indices, face (k,) the object's own face indices,
    p (k, 3) float64 hit points -> (k, 3) float64 linear RGB.
    """

    def __init__(self, scene: Scene):
        self.objects = scene.objects
        # each texture decoded once (float64 linear), by object
        self.linear = {i: srgb_decode(o.material.texture.texels)
                       for i, o in enumerate(scene.objects) if o.material.texture is not None}

    @classmethod
    def of(cls, scene: Scene) -> "SurfaceColours | None":
        if any(o.material.texture is not None or o.colors is not None for o in scene.objects):
            return cls(scene)
        return None

    def colour(self, obj: np.ndarray, face: np.ndarray, p: np.ndarray) -> np.ndarray:
        out = np.ones((len(obj), 3))
        for i in np.unique(obj):
            o = self.objects[int(i)]
            if o.material.texture is None and o.colors is None:
                continue
            mine = np.flatnonzero(obj == i)
            f = o.faces[face[mine]]
            bary = barycentrics(o.vertices[f], np.asarray(p[mine], np.float64))
            if o.colors is not None:
                out[mine] *= np.einsum("kc,kcd->kd", bary, o.colors[f])
            if o.material.texture is not None:
                uv = np.einsum("kc,kcd->kd", bary, o.uv[f])
                out[mine] *= sample(o.material.texture, self.linear[int(i)], uv)
        return out
