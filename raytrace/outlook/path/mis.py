"""Multiple importance sampling (Veach and Guibas 1995) of the path tracer's two strategies for
the light of emissive surfaces: next-event estimation (a point chosen on the emitters) and BSDF
sampling (the next direction of the path, which may hit an emitter).

Each strategy's sample is weighed by w = h(p_this, p_other), both densities in solid angle at
the vertex: the emitter sample's area density converted, p_light = p_A(y) |x - y|^2 / cos_y
(`emitter_pdf`, and `hit_pdf` for the point a BSDF sample hit), the BSDF's own density as it
is.  For the same path the two weights sum
to one, so the estimate stays unbiased whatever h is:

* "power" (beta = 2, the default): w = p_this^2 / (p_this^2 + p_other^2), which Veach found
  best in practice (it nearly drops a strategy where the other is much better: NEE on a
  large, diffuse emitter, the BSDF sample on a small or glossy one);
* "balance": w = p_this / (p_this + p_other);
* "nee": no MIS, next-event estimation alone (weight 1); emitters hit by BSDF-sampled rays
  are not counted (weight 0), as camera rays and delta bounces still count them whole.

Both weights are computed as 1 / (1 + r^beta), r = p_other / p_this, in float32 (`pathstate.STATE`):
a grazing emitter point makes p_light overflow float32, where the ratio form gives the right limits
(weight 1 or 0) instead of inf / inf.  A zero p_this weighs 0. `raytrace.outlook.path.pathstages`
repeats this arithmetic operation for operation (HEURISTICS' codes).
"""

from __future__ import annotations

import numpy as np

from .pathstate import STATE, STATE_TINY

HEURISTICS = ("power", "balance", "nee")
DEFAULT_HEURISTIC = "power"


def code(heuristic: str) -> int:
    """The heuristic's index in HEURISTICS (what the compiled kernels take); a ValueError for
    an unknown name."""
    if heuristic not in HEURISTICS:
        raise ValueError(f"mis must be one of {', '.join(HEURISTICS)}, got {heuristic!r}")
    return HEURISTICS.index(heuristic)


def weight(p_this, p_other, heuristic: str = DEFAULT_HEURISTIC):
    """The MIS weight (float32, same shape) of a sample of the strategy with density p_this
    against the other's p_other (solid angle both; arrays or scalars).  "nee": 1 (the NEE
    strategy's weight; `bsdf_weight` gives the other's)."""
    p_this = np.asarray(p_this, STATE)
    p_other = np.asarray(p_other, STATE)
    if heuristic == "nee":
        return np.ones(np.broadcast(p_this, p_other).shape, STATE)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        r = p_other / p_this
        if code(heuristic) == 0:
            r = r * r
        w = STATE(1.0) / (STATE(1.0) + r)
    return np.where(p_this > 0.0, w, STATE(0.0))


def bsdf_weight(p_bsdf, p_light, heuristic: str = DEFAULT_HEURISTIC):
    """The weight of an emitter found by BSDF sampling: `weight(p_bsdf, p_light)`, 0 for
    "nee" (next-event estimation alone counts that light)."""
    if heuristic == "nee":
        return np.zeros(np.broadcast(np.asarray(p_bsdf), np.asarray(p_light)).shape, STATE)
    return weight(p_bsdf, p_light, heuristic)


def emitter_pdf(p_area, dist2, cos_y):
    """Next-event estimation's density in solid angle at x of the emitter point y it chose with
    area density p_area (k,), at squared distance dist2 from x and with cosine cos_y between its
    normal and the direction to x: p_area dist2 / cos_y (cos_y kept from 0: a grazing point's
    density is huge)."""
    return p_area * dist2 / np.maximum(cos_y, STATE(STATE_TINY))


def hit_pdf(p_area, t, cos_y):
    """The same density for the emitter point that a BSDF-sampled ray hit at distance t (k,)
    with cosine cos_y there (`emitter_pdf` of the same point: the two strategies' weights of
    one path must use one density)."""
    return p_area * (t * t) / np.maximum(cos_y, STATE(STATE_TINY))
