"""The lights of the scene model: point, directional, spot and area lights.

An area light is its N samples, computed once here (`shadowvol.arealights` places them), each
judged as a hard light (`hard_lights`); a point, spot or directional light is the case N = 1.
Colours are linear RGB.  `shadowvol.scene` names the lights too (`shadowvol.scene.AreaLight`,
the public name).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from shadowvol import arealights
from shadowvol.checks import SceneError, flag, frozen, num, unit, vec
from shadowvol.planes import default_plane_axes


class _Emitter:
    """What every light has: a colour (linear RGB, (3,) float64) times an intensity, and
    `shadows` (False: nothing blocks it; it lights every point its n . l and cone reach)."""

    def _check_colour(self) -> None:
        object.__setattr__(self, "shadows", flag(self.shadows, "shadows"))
        c = vec(self.color, "color")
        if np.any(c < 0):
            raise SceneError("color", f"colour components must be >= 0, got {c.tolist()}")
        object.__setattr__(self, "color", c)
        object.__setattr__(self, "intensity", num(self.intensity, "intensity", low=0.0))

    @property
    def radiance(self) -> np.ndarray:
        """(3,) float64: color * intensity (no distance fall-off)."""
        return self.color * self.intensity

    @functools.cached_property
    def homogeneous(self) -> np.ndarray:
        """(4,) float64, read-only: the light as a homogeneous point, (position, 1), or for a
        directional light (-direction, 0), the point at infinity it comes from.  The one
        conversion every pass and the planar projection use; computed once per light."""
        if isinstance(self, DirectionalLight):
            h = np.append(-self.direction, 0.0)
        else:
            h = np.append(self.position, 1.0)
        h.setflags(write=False)
        return h


@dataclass(frozen=True, eq=False)
class PointLight(_Emitter):
    position: np.ndarray
    color: np.ndarray = field(default_factory=lambda: vec([1, 1, 1], "color"))
    intensity: float = 1.0
    shadows: bool = True

    def __post_init__(self):
        object.__setattr__(self, "position", vec(self.position, "position"))
        self._check_colour()


@dataclass(frozen=True, eq=False)
class DirectionalLight(_Emitter):
    """`direction` is the direction the light travels (unit length after construction)."""

    direction: np.ndarray
    color: np.ndarray = field(default_factory=lambda: vec([1, 1, 1], "color"))
    intensity: float = 1.0
    shadows: bool = True

    def __post_init__(self):
        object.__setattr__(self, "direction", unit(vec(self.direction, "direction"), "direction"))
        self._check_colour()


@dataclass(frozen=True, eq=False)
class SpotLight(_Emitter):
    """A point light limited to a cone: a point P is inside when the angle between `direction`
    and P - position is at most `cone_angle` degrees (the half-angle of the cone)."""

    position: np.ndarray
    direction: np.ndarray
    cone_angle: float = 30.0
    color: np.ndarray = field(default_factory=lambda: vec([1, 1, 1], "color"))
    intensity: float = 1.0
    shadows: bool = True

    def __post_init__(self):
        object.__setattr__(self, "position", vec(self.position, "position"))
        object.__setattr__(self, "direction", unit(vec(self.direction, "direction"), "direction"))
        object.__setattr__(self, "cone_angle",
                           num(self.cone_angle, "cone_angle", low=0.0, high=90.0, low_open=True))
        self._check_colour()

    @property
    def cos_cutoff(self) -> float:
        return math.cos(math.radians(self.cone_angle))


class AreaSample(SpotLight):
    """One sample of a one-sided area light (rect, disk): a spot light at the sample with a
    90-degree cone around the emitting normal `direction`, whose shading is also weighted by
    the cosine at the light, max(direction . (p - position) / |p - position|, 0).  Its mask is
    exactly a 90-degree spot light's."""


MAX_LIGHT_SAMPLES = 65535  # lit counts are uint16
AREA_SHAPES = ("rect", "disk", "sphere")


@dataclass(frozen=True, eq=False)
class AreaLight(_Emitter):
    """A light with area, seen by both renderers as `samples` point lights (its `hard` lights).

    shape   : "rect" (centre, normal, size along the plane axes u, v of
              `shadowvol.planes.default_plane_axes`), "disk" (centre, normal, radius) or
              "sphere" (centre, radius)
    samples : N >= 1; pattern "stratified" (a jittered grid) or "halton"; seed (see
              `shadowvol.arealights`)
    Computed once: positions (N, 3) float64 and weights (N,) float64 (each 1/N) of the samples.

    Emission: a rect or disk emits on the side its `normal` points to, each sample weighted by
    the cosine at the light (`AreaSample`); a sphere's samples lie on its surface and each
    radiates in every direction (cosine 1; the sphere itself is no geometry and casts nothing).
    A sample's share of the radiance is weight * color * intensity (no distance fall-off).
    A sphere light may intersect the scene's meshes: its samples are then point lights inside
    or behind them, shadowed like any other.
    """

    shape: str
    center: np.ndarray
    normal: np.ndarray | None = None
    size: np.ndarray | None = None
    radius: float | None = None
    samples: int = 16
    pattern: str = "stratified"
    seed: int = 0
    color: np.ndarray = field(default_factory=lambda: vec([1, 1, 1], "color"))
    intensity: float = 1.0
    shadows: bool = True
    positions: np.ndarray = field(init=False, repr=False)
    weights: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        if self.shape not in AREA_SHAPES:
            raise SceneError("type", f"unknown area light shape {self.shape!r} "
                                     f"(one of: {', '.join(AREA_SHAPES)})")
        object.__setattr__(self, "center", vec(self.center, "center"))
        need = {"rect": ("normal", "size"), "disk": ("normal", "radius"),
                "sphere": ("radius",)}[self.shape]
        for key in ("normal", "size", "radius"):
            given = getattr(self, key) is not None
            if given != (key in need):
                raise SceneError(key, "missing" if not given else
                                 f"not a key of a {self.shape} light")
        if self.normal is not None:
            object.__setattr__(self, "normal", unit(vec(self.normal, "normal"), "normal"))
        if self.size is not None:
            object.__setattr__(self, "size", vec(self.size, "size", 2, positive=True))
        if self.radius is not None:
            object.__setattr__(self, "radius", num(self.radius, "radius", low=0.0,
                                                   low_open=True))
        n = self.samples
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or \
                not 1 <= n <= MAX_LIGHT_SAMPLES:
            raise SceneError("samples", f"must be a whole number 1..{MAX_LIGHT_SAMPLES}, "
                                        f"got {n!r}")
        if self.pattern not in arealights.PATTERNS:
            raise SceneError("pattern", f"unknown pattern {self.pattern!r} "
                                        f"(one of: {', '.join(arealights.PATTERNS)})")
        s = self.seed
        if isinstance(s, bool) or not isinstance(s, (int, np.integer)) or s < 0:
            raise SceneError("seed", f"must be a whole number >= 0, got {s!r}")
        self._check_colour()
        n = int(n)
        if self.shape == "sphere":
            uv = arealights.unit_square(n, self.pattern, int(s))
            points = arealights.sphere_points(uv, self.center, self.radius)
        else:
            u, v = default_plane_axes(self.normal)
            grid = arealights.grid_shape(n)
            if self.shape == "rect" and self.size[1] > self.size[0]:
                grid = grid[::-1]  # more cells along the longer side
            uv = arealights.unit_square(n, self.pattern, int(s), grid)
            points = (arealights.rect_points(uv, self.center, u, v, self.size)
                      if self.shape == "rect" else
                      arealights.disk_points(uv, self.center, u, v, self.radius))
        object.__setattr__(self, "samples", n)
        object.__setattr__(self, "seed", int(s))
        object.__setattr__(self, "positions", frozen(np.ascontiguousarray(points)))
        object.__setattr__(self, "weights", frozen(np.full(n, 1.0 / n)))

    @functools.cached_property
    def hard(self) -> tuple[PointLight | AreaSample, ...]:
        """The N sample lights, in sample order, each with intensity * weight: AreaSample for a
        rect or disk, PointLight for a sphere."""
        if self.shape == "sphere":
            return tuple(PointLight(p, self.color, self.intensity * w, self.shadows)
                         for p, w in zip(self.positions, self.weights))
        return tuple(AreaSample(p, self.normal, 90.0, self.color, self.intensity * w,
                                self.shadows)
                     for p, w in zip(self.positions, self.weights))


Light = PointLight | DirectionalLight | SpotLight | AreaLight


def hard_lights(light: Light) -> tuple[PointLight | DirectionalLight | SpotLight, ...]:
    """The point-like lights that make up `light`: an area light's samples, else the light."""
    return light.hard if isinstance(light, AreaLight) else (light,)


def light_samples(light: Light) -> np.ndarray | None:
    """(N, 3) float64 world positions of the light's samples (N = 1 for a point or spot
    light), or None for a directional light (it has no position)."""
    if isinstance(light, AreaLight):
        return light.positions
    if isinstance(light, DirectionalLight):
        return None
    return light.position[None]


def emission_cosine(light, to_light: np.ndarray) -> np.ndarray | float:
    """The cosine at the light of a hard light (one of `hard_lights`): for an AreaSample
    max(-to_light . direction, 0), (k,) float64, with to_light (k, 3) the unit directions from
    the surface to the light; 1.0 for every other light."""
    if isinstance(light, AreaSample):
        return np.maximum(-(to_light @ light.direction), 0.0)
    return 1.0
