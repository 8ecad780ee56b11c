"""The intrinsic layers' checks (docs/CONVENTIONS.md, "Intrinsic layers"), shared by the ray
tracer's and the rasterizer's tests: the two identities to float32 rounding, the hard lights'
`direct_shadowed` in {0, direct}, and the albedo of a textured quad at known pixels against the
texel under the pixel, computed in float64 without any renderer."""

from __future__ import annotations

import math

import numpy as np
from builders import GL_NEAREST, GL_REPEAT, textured_glb, textured_scene_file

from shadowvol.scene import AreaLight
from shadowvol.scenefile import load_scene

U32 = 2.0 ** -24   # float32's unit roundoff
U64 = 2.0 ** -53


def identity_tolerance(terms: list[np.ndarray]) -> np.ndarray:
    """Per element, the bound on |total − Σ terms| where total and each of the L + 1 terms are
    float64 sums rounded once to float32 and Σ is summed in float32: L + 1 roundings of the
    terms, L of the float32 additions and 1 of the total, each at most U32 of Σ|terms| (first
    order), plus the float64 reassociation (L + 1 terms, U64 each): (2L + 2)·U32 + (L + 1)·U64,
    times Σ|terms|, and float32's smallest normal for the zero terms."""
    n = len(terms)   # L + 1
    scale = np.sum([np.abs(t.astype(np.float64)) for t in terms], axis=0)
    return (2 * n * U32 + n * U64) * scale + np.finfo(np.float32).tiny


def check_identities(layers: dict, image: np.ndarray, shadow_free: np.ndarray) -> float:
    """image = ambient + Σ direct_shadowed and shadow_free = ambient + Σ direct (both the
    layers' own `shadow_free` and `shadow_free` given, the image rendered with every light's
    shadows off), to `identity_tolerance`; returns the largest error relative to its bound."""
    worst = 0.0
    amb = layers["ambient"]
    for total, parts in ((image, layers["direct_shadowed"]), (layers["shadow_free"],
                                                             layers["direct"]),
                         (shadow_free, layers["direct"])):
        terms = [amb, *parts]
        got = np.float32(0) + amb
        for part in parts:
            got = (got + part).astype(np.float32)
        err = np.abs(got.astype(np.float64) - np.asarray(total, np.float64))
        tol = identity_tolerance(terms + [np.asarray(total)])
        assert (err <= tol).all(), f"identity off by {err.max()} (bound {tol[err > tol].min()})"
        worst = max(worst, float((err / tol).max()))
    return worst


def check_shadowed(scene, layers: dict) -> None:
    """A hard light's direct_shadowed is its direct or 0 at each pixel (exactly: lit · direct);
    an area light's lies between 0 and its direct (the sum over a subset of its samples)."""
    direct, shadowed = layers["direct"], layers["direct_shadowed"]
    assert direct.dtype == shadowed.dtype == np.float32
    assert (direct >= 0).all() and (shadowed >= 0).all()
    for i, light in enumerate(scene.lights):
        if isinstance(light, AreaLight):
            assert (shadowed[i] <= direct[i] * (1 + 8 * U32)).all()
        else:
            same = (shadowed[i] == direct[i]).all(-1)
            zero = (shadowed[i] == 0).all(-1)
            assert (same | zero).all(), f"light {i}: direct_shadowed is neither direct nor 0"


def decode(code: int) -> float:
    c = code / 255.0
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def textured_quad(folder):
    """A textured quad seen straight down (nearest, repeat, 64 x 64) and its 8 x 8 texels."""
    tex = np.random.default_rng(3).integers(0, 256, (8, 8, 3)).astype(np.uint8)
    textured_glb(folder / "quad.glb", tex, wrap=GL_REPEAT, filt=GL_NEAREST)
    path = textured_scene_file(folder, "quad.glb", width=64, height=64)
    path.write_text(path.read_text().replace("eye = [0.3, 2.2, 1.9]", "eye = [0, 3, 0]")
                    .replace("fov_y = 50", "fov_y = 30\nup = [0, 0, -1]"))
    return load_scene(path), tex


def quad_texels(scene, tex):
    """Of `textured_quad`'s frame, seen straight down (an affine map from pixels to UVs): every
    fifth pixel (x, y), its point p (3,) on the quad in float64 and the sRGB-decoded texel
    under it (3,); pixels whose UV lies within 1e-3 texel of a texel edge are left out."""
    half = math.tan(math.radians(scene.camera.fov_y) / 2) * 3.0   # half the view on the ground
    uv = scene.objects[0].uv
    for y in range(2, 62, 5):
        for x in range(2, 62, 5):
            # up = -z: image rows go toward +z, columns toward +x
            px = ((x + 0.5) / 64 * 2 - 1) * half
            pz = ((y + 0.5) / 64 * 2 - 1) * half
            u = uv[0, 0] + (px + 1) / 2 * (uv[2, 0] - uv[0, 0])
            v = uv[0, 1] + (pz + 1) / 2 * (uv[2, 1] - uv[0, 1])
            tx, ty = u * 8, v * 8
            if min(abs(tx - round(tx)), abs(ty - round(ty))) < 1e-3:
                continue
            base = np.array([decode(int(c)) for c in tex[math.floor(ty) % 8,
                                                         math.floor(tx) % 8]])
            yield x, y, np.array([px, 0.0, pz]), base


def check_albedo(scene, tex, albedo: np.ndarray, atol: float) -> int:
    """albedo at pixels of the quad = material diffuse × the texel under the pixel's UV
    (sRGB-decoded), in float64 (`quad_texels`).  Returns how many pixels were checked."""
    m = scene.objects[0].material
    checked = 0
    for x, y, _, base in quad_texels(scene, tex):
        np.testing.assert_allclose(albedo[y, x], np.asarray(m.diffuse) * base, rtol=0,
                                   atol=atol, err_msg=f"pixel ({x}, {y})")
        checked += 1
    return checked
