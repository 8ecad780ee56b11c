"""Task: the Phong lighting model at one surface point."""

import numpy as np


def shade(point, normal, eye, light, light_color, ambient, ka, kd, ks, shininess):
    """The colour (linear RGB) that one point light gives a surface point, by Phong's model.

    Inputs: point p, unit normal n (on the eye's side of the surface), the eye's position E and
    the light's position L (3 numbers each); light_color and ambient (RGB, 3 numbers each: the
    light's and the scene's ambient radiance); the material's ka, kd, ks (RGB each) and its
    shininess s.
    Output: the colour, 3 numbers.

    With l = (L − p)/|L − p| (to the light), v = (E − p)/|E − p| (to the eye) and
    r = 2 (n·l) n − l (l mirrored about n):
        colour = ka·ambient + [kd max(n·l, 0) + ks max(r·v, 0)^s] · light_color
    where the bracket counts only when the light is on the normal's side, n·l > 0 (no light,
    hence no highlight either, on a surface facing away).  Products of colours are per channel.

    >>> [round(float(x), 6) for x in shade((0, 0, 0), (0, 0, 1), (0, 0, 5), (0, 0, 5),
    ...     (1, 1, 1), (0.1, 0.1, 0.1), (1, 1, 1), (0.5, 0.5, 0.5), (0.25, 0.25, 0.25), 8)]
    [0.85, 0.85, 0.85]
    """
    p, n, e, L = (np.asarray(v, float) for v in (point, normal, eye, light))
    colour = np.asarray(ka, float) * np.asarray(ambient, float)
    to_light = L - p
    l = to_light / np.linalg.norm(to_light)
    n_dot_l = float(n @ l)
    if n_dot_l <= 0.0:
        return colour
    v = (e - p) / np.linalg.norm(e - p)
    r = 2.0 * n_dot_l * n - l
    r_dot_v = max(float(r @ v), 0.0)
    term = np.asarray(kd, float) * n_dot_l + np.asarray(ks, float) * r_dot_v ** shininess
    return colour + term * np.asarray(light_color, float)
