"""Write `cornell.toml`: the Cornell box from the published Cornell measurements.

Source: the Cornell Program of Computer Graphics, "The Cornell Box" data
(https://www.graphics.cornell.edu/online/box/data.html): the geometry in millimetres, the camera,
the reflectance spectra of the white, green and red surfaces (400-700 nm, every 4 nm) and the
light's emission spectrum (400, 500, 600, 700 nm, linearly interpolated).

Changes from the published data, each for a reason:
* the ceiling has a hole where the light is (the real box's light sits in an opening), so that
  the light and the ceiling are never coplanar surfaces on top of each other;
* the light is one emissive quad (`material.emission`), not a point light: the scene format has
  no area lights yet, and an emissive surface is what the path tracer and radiosity need anyway.

Colours: each spectrum is converted to linear sRGB by integrating against the CIE 1931 2-degree
colour-matching functions (the multi-lobe Gaussian fit of Wyman, Sloan and Shirley 2013, JCGT
2(2)) under the equal-energy illuminant E, converting XYZ to linear sRGB (IEC 61966-2-1 matrix),
and dividing each channel by that of the perfect white reflector, so that a flat spectrum of
value r maps to (r, r, r) (a von Kries white balance to E in sRGB space).  Negative components
(out-of-gamut spectra) are clipped to 0.

    python scenes/make_cornell.py        # rewrites scenes/cornell.toml
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

WAVELENGTHS = np.arange(400.0, 701.0, 4.0)  # 76 samples, nm

WHITE = [0.343, 0.445, 0.551, 0.624, 0.665, 0.687, 0.708, 0.723, 0.715, 0.710, 0.745, 0.758,
         0.739, 0.767, 0.777, 0.765, 0.751, 0.745, 0.748, 0.729, 0.745, 0.757, 0.753, 0.750,
         0.746, 0.747, 0.735, 0.732, 0.739, 0.734, 0.725, 0.721, 0.733, 0.725, 0.732, 0.743,
         0.744, 0.748, 0.728, 0.716, 0.733, 0.726, 0.713, 0.740, 0.754, 0.764, 0.752, 0.736,
         0.734, 0.741, 0.740, 0.732, 0.745, 0.755, 0.751, 0.744, 0.731, 0.733, 0.744, 0.731,
         0.712, 0.708, 0.729, 0.730, 0.727, 0.707, 0.703, 0.729, 0.750, 0.760, 0.751, 0.739,
         0.724, 0.730, 0.740, 0.737]
GREEN = [0.092, 0.096, 0.098, 0.097, 0.098, 0.095, 0.095, 0.097, 0.095, 0.094, 0.097, 0.098,
         0.096, 0.101, 0.103, 0.104, 0.107, 0.109, 0.112, 0.115, 0.125, 0.140, 0.160, 0.187,
         0.229, 0.285, 0.343, 0.390, 0.435, 0.464, 0.472, 0.476, 0.481, 0.462, 0.447, 0.441,
         0.426, 0.406, 0.373, 0.347, 0.337, 0.314, 0.285, 0.277, 0.266, 0.250, 0.230, 0.207,
         0.186, 0.171, 0.160, 0.148, 0.141, 0.136, 0.130, 0.126, 0.123, 0.121, 0.122, 0.119,
         0.114, 0.115, 0.117, 0.117, 0.118, 0.120, 0.122, 0.128, 0.132, 0.139, 0.144, 0.146,
         0.150, 0.152, 0.157, 0.159]
RED = [0.040, 0.046, 0.048, 0.053, 0.049, 0.050, 0.053, 0.055, 0.057, 0.056, 0.059, 0.057,
       0.061, 0.061, 0.060, 0.062, 0.062, 0.062, 0.061, 0.062, 0.060, 0.059, 0.057, 0.058,
       0.058, 0.058, 0.056, 0.055, 0.056, 0.059, 0.057, 0.055, 0.059, 0.059, 0.058, 0.059,
       0.061, 0.061, 0.063, 0.063, 0.067, 0.068, 0.072, 0.080, 0.090, 0.099, 0.124, 0.154,
       0.192, 0.255, 0.287, 0.349, 0.402, 0.443, 0.487, 0.513, 0.558, 0.584, 0.620, 0.606,
       0.609, 0.651, 0.612, 0.610, 0.650, 0.638, 0.627, 0.620, 0.630, 0.628, 0.642, 0.639,
       0.657, 0.639, 0.635, 0.642]
LIGHT_NM, LIGHT = [400.0, 500.0, 600.0, 700.0], [0.0, 8.0, 15.6, 18.4]

XYZ_TO_SRGB = np.array([[3.2406, -1.5372, -0.4986],
                        [-0.9689, 1.8758, 0.0415],
                        [0.0557, -0.2040, 1.0570]])


def _lobe(lam, mu, below, above):
    s = np.where(lam < mu, below, above)
    return np.exp(-0.5 * ((lam - mu) / s) ** 2)


def cmf(lam: np.ndarray) -> np.ndarray:
    """CIE 1931 2-degree colour-matching functions (n, 3) at wavelengths lam (n,) nm: the
    multi-lobe fit of Wyman, Sloan and Shirley (2013)."""
    x = (1.056 * _lobe(lam, 599.8, 37.9, 31.0) + 0.362 * _lobe(lam, 442.0, 16.0, 26.7)
         - 0.065 * _lobe(lam, 501.1, 20.4, 26.2))
    y = 0.821 * _lobe(lam, 568.8, 46.9, 40.5) + 0.286 * _lobe(lam, 530.9, 16.3, 31.1)
    z = 1.217 * _lobe(lam, 437.0, 11.8, 36.0) + 0.681 * _lobe(lam, 459.0, 26.0, 13.8)
    return np.stack([x, y, z], axis=1)


def spectrum_to_rgb(values) -> np.ndarray:
    """Linear sRGB (3,) of a spectrum sampled at WAVELENGTHS, white-balanced to E (see above)."""
    w = cmf(WAVELENGTHS)
    rgb = XYZ_TO_SRGB @ (np.asarray(values) @ w)
    white = XYZ_TO_SRGB @ w.sum(axis=0)
    return np.maximum(rgb / white, 0.0)


# Geometry, mm (the published vertex lists; every quad is written as its 4 corners in order).
FLOOR = [[552.8, 0, 0], [0, 0, 0], [0, 0, 559.2], [549.6, 0, 559.2]]
BACK = [[549.6, 0, 559.2], [0, 0, 559.2], [0, 548.8, 559.2], [556.0, 548.8, 559.2]]
RIGHT_GREEN = [[0, 0, 559.2], [0, 0, 0], [0, 548.8, 0], [0, 548.8, 559.2]]
LEFT_RED = [[552.8, 0, 0], [549.6, 0, 559.2], [556.0, 548.8, 559.2], [556.0, 548.8, 0]]
LIGHT_QUAD = [[343.0, 548.8, 227.0], [343.0, 548.8, 332.0], [213.0, 548.8, 332.0],
              [213.0, 548.8, 227.0]]
CEILING = [[556.0, 548.8, 0], [556.0, 548.8, 559.2], [0, 548.8, 559.2], [0, 548.8, 0]]
SHORT_BLOCK = [
    [[130, 165, 65], [82, 165, 225], [240, 165, 272], [290, 165, 114]],
    [[290, 0, 114], [290, 165, 114], [240, 165, 272], [240, 0, 272]],
    [[130, 0, 65], [130, 165, 65], [290, 165, 114], [290, 0, 114]],
    [[82, 0, 225], [82, 165, 225], [130, 165, 65], [130, 0, 65]],
    [[240, 0, 272], [240, 165, 272], [82, 165, 225], [82, 0, 225]]]
TALL_BLOCK = [
    [[423, 330, 247], [265, 330, 296], [314, 330, 456], [472, 330, 406]],
    [[423, 0, 247], [423, 330, 247], [472, 330, 406], [472, 0, 406]],
    [[472, 0, 406], [472, 330, 406], [314, 330, 456], [314, 0, 456]],
    [[314, 0, 456], [314, 330, 456], [265, 330, 296], [265, 0, 296]],
    [[265, 0, 296], [265, 330, 296], [423, 330, 247], [423, 0, 247]]]
# Camera: at (278, 273, -800) looking along +z; focal length 35 mm, film 25 x 25 mm.
CAMERA_FOV_Y = math.degrees(2.0 * math.atan(12.5 / 35.0))


def quads(quad_list):
    """Vertices and faces (two triangles per quad, fan from the first corner)."""
    vertices, faces = [], []
    for q in quad_list:
        k = len(vertices)
        vertices += q
        faces += [[k, k + 1, k + 2], [k, k + 2, k + 3]]
    return vertices, faces


def ceiling_with_hole():
    """The ceiling rectangle minus the light's rectangle: 8 corners, 8 triangles."""
    outer = CEILING  # (556, 0), (556, 559.2), (0, 559.2), (0, 0) in (x, z)
    inner = [[343.0, 548.8, 227.0], [343.0, 548.8, 332.0], [213.0, 548.8, 332.0],
             [213.0, 548.8, 227.0]]  # the corners nearest outer[0..3] in the same order
    vertices = outer + inner
    faces = []
    for i in range(4):
        j = (i + 1) % 4
        faces += [[i, j, 4 + j], [i, 4 + j, 4 + i]]
    return vertices, faces


def _fmt(v) -> str:
    return "[" + ", ".join(f"{float(x):g}" for x in v) + "]"


def _mesh(name, material, vertices, faces) -> str:
    vs = ", ".join(_fmt(v) for v in vertices)
    fs = ", ".join("[" + ", ".join(str(i) for i in f) + "]" for f in faces)
    return (f'[[objects]]\ntype = "mesh"\nname = "{name}"\nmaterial = "{material}"\n'
            f"vertices = [{vs}]\nfaces = [{fs}]\n")


def toml() -> str:
    white, green, red = (spectrum_to_rgb(s) for s in (WHITE, GREEN, RED))
    light = spectrum_to_rgb(np.interp(WAVELENGTHS, LIGHT_NM, LIGHT))

    def mat(name, kd, emission=(0.0, 0.0, 0.0)):
        return (f"[materials.{name}]\nambient = {_fmt(kd)}\ndiffuse = {_fmt(kd)}\n"
                f"specular = [0, 0, 0]\nemission = {_fmt(emission)}\n")

    out = ['# The Cornell box from the published Cornell measurements; written by '
           'make_cornell.py (edit that, not this).\n'
           '# Units: millimetres.  Colours: measured spectra -> CIE 1931 XYZ -> linear sRGB, '
           'white-balanced to illuminant E.\n'
           'name = "cornell"\nambient = [0.1, 0.1, 0.1]   # local illumination / Whitted only\n',
           '[image]\nwidth = 256\nheight = 256\nbackground = [0, 0, 0]\n',
           f'[camera]\neye = [278, 273, -800]\ntarget = [278, 273, 0]\nup = [0, 1, 0]\n'
           f'fov_y = {CAMERA_FOV_Y:.6f}\nnear = 10\n',
           '[render]\nmax_depth = 4\n',
           mat("white", white), mat("green", green), mat("red", red),
           mat("light", white, light)]
    out.append(_mesh("floor", "white", *quads([FLOOR])))
    out.append(_mesh("ceiling", "white", *ceiling_with_hole()))
    out.append(_mesh("back wall", "white", *quads([BACK])))
    out.append(_mesh("green wall", "green", *quads([RIGHT_GREEN])))
    out.append(_mesh("red wall", "red", *quads([LEFT_RED])))
    out.append(_mesh("light", "light", *quads([LIGHT_QUAD])))
    out.append(_mesh("short block", "white", *quads(SHORT_BLOCK)))
    out.append(_mesh("tall block", "white", *quads(TALL_BLOCK)))
    return "\n".join(out)


if __name__ == "__main__":
    path = Path(__file__).with_name("cornell.toml")
    path.write_text(toml())
    print(f"wrote {path}")
