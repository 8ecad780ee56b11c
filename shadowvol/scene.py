"""The scene model: the single, immutable input of both renderers.

Everything here is plain data (frozen dataclasses holding read-only numpy arrays) and has no GL
import, so the ray tracer can use it without a context.  Geometry is stored in world space, already
transformed, as triangles; an object made from a primitive also keeps its exact analytic form
(`Sphere`, `Parallelogram`) for the ray tracer's images.  Mask comparisons always use the triangles
(see CONVENTIONS.md: "Everything that casts or receives a shadow in a mask comparison is triangles").

Constructors validate their input and raise `SceneError` naming the key and the problem; the file
loader (`shadowvol.scenefile`) adds the file name.  Colours are linear RGB; images are encoded to
sRGB only when written.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass, field

import numpy as np

# Geometric tolerances of the scene model itself (renderer tolerances live with each renderer).
PARALLEL_TOLERANCE = 1e-9  # |sin| of the angle below which `up` counts as parallel to the view
# An absolute cap on the pixels of an image, 16384 x 16384 (the largest frame llvmpipe makes):
# below it the memory budget decides what fits (`shadowvol.memory`); above it an image is
# refused as a limit whatever the machine's memory (a typo such as 1e6 x 1e6 among them).
MAX_IMAGE_PIXELS = 1 << 28
# The float32 range the renderers use: every number of a scene has |x| <= MAX_MAGNITUDE, and
# every length that must be positive (near, radius, sizes, scale) is >= MIN_POSITIVE, so that
# x, 1/x, x*x and sums of a few squares are all normal float32 numbers (float32 ends at 3.4e38
# and its normal numbers at 1.2e-38).  A world 1e6 or 1e9 wide is far inside this.
MAX_MAGNITUDE = 1e18
MIN_POSITIVE = 1e-18
# Messages quote a bad value only up to this many characters (a wrong 1e6-element list is not
# echoed whole), and a SceneError's key and problem are cut to one line of at most this length.
MAX_QUOTE = 80
MAX_MESSAGE = 400


def shorten(value, limit: int = MAX_QUOTE) -> str:
    """repr(value), cut to about `limit` characters ("… (N items)" for a long list)."""
    text = repr(value)
    if len(text) <= limit:
        return text
    more = f" ({len(value)} items)" if isinstance(value, (list, tuple, np.ndarray)) else ""
    return text[:limit] + "…" + more


def _one_line(text: str, limit: int) -> str:
    """`text` with line breaks and other control characters escaped, cut to `limit`."""
    if not text.isprintable():
        text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
    return text if len(text) <= limit else text[:limit] + "…"


class SceneError(ValueError):
    """Bad scene input: names the file (when known), the key and the problem."""

    def __init__(self, key: str, problem: str, file: str | None = None):
        # one line, whatever the input: keys and values from a file may hold line breaks
        key, problem = _one_line(key, MAX_QUOTE), _one_line(problem, MAX_MESSAGE)
        file = None if file is None else _one_line(file, MAX_MESSAGE)
        self.key, self.problem, self.file = key, problem, file
        parts = [part for part in (file, key) if part]
        super().__init__(": ".join(parts + [problem]))

    def in_file(self, file: str) -> "SceneError":
        return SceneError(self.key, self.problem, file)

    def under(self, prefix: str) -> "SceneError":
        key = f"{prefix}.{self.key}" if self.key else prefix
        return SceneError(key, self.problem, self.file)


def reject_unknown_keys(table, allowed, key: str = "") -> None:
    """Raise SceneError naming the first key of `table` that is not in `allowed`; `key` is the
    table's own key path ("" at the top level), so the error names `key.unknown`."""
    unknown = sorted(str(name) for name in set(table) - set(allowed))
    if unknown:
        prefix = f"{key}." if key else ""
        raise SceneError(f"{prefix}{unknown[0]}",
                         f"unknown key (allowed here: {', '.join(sorted(allowed))})")


def is_number(x) -> bool:
    """A real number, strictly: int or float (numpy's too), never a bool or a string."""
    return (isinstance(x, (int, float, np.integer, np.floating))
            and not isinstance(x, (bool, np.bool_)))


def _numbers(value) -> bool:
    """`value` is a numeric array or a flat list/tuple of real numbers (`is_number`)."""
    if isinstance(value, np.ndarray):
        return value.dtype.kind in "iuf"
    return isinstance(value, (list, tuple)) and all(is_number(x) for x in value)


def vec(value, key: str, n: int = 3, *, positive: bool = False) -> np.ndarray:
    """A read-only float64 vector of length `n` from `value` (a list, tuple or array of real
    numbers: no strings, no booleans), or a SceneError naming `key`."""
    if not _numbers(value):
        raise SceneError(key, f"expected {n} numbers, got {shorten(value)}")
    arr = np.array(value, dtype=np.float64)
    if arr.shape != (n,):
        raise SceneError(key, f"expected {n} numbers, got {shorten(value)}")
    if not np.all(np.isfinite(arr)):
        raise SceneError(key, f"non-finite number in {shorten(value)}")
    if np.any(np.abs(arr) > MAX_MAGNITUDE):
        raise SceneError(key, f"{shorten(value)} is beyond the float32 range the renderers use "
                              f"(|x| <= {MAX_MAGNITUDE:g})")
    if positive and np.any(arr <= 0):
        raise SceneError(key, f"must be positive, got {shorten(value)}")
    if positive and np.any(arr < MIN_POSITIVE):
        raise SceneError(key, f"{shorten(value)} is too small for float32 (at least "
                              f"{MIN_POSITIVE:g})")
    arr.setflags(write=False)
    return arr


def num(value, key: str, *, low: float | None = None, high: float | None = None,
        low_open: bool = False) -> float:
    """A finite float from `value` within [low, high] (low excluded if `low_open`)."""
    if not is_number(value):
        raise SceneError(key, f"expected a number, got {shorten(value)}")
    x = float(value)
    if not math.isfinite(x):
        raise SceneError(key, f"non-finite number {value!r}")
    if abs(x) > MAX_MAGNITUDE:
        raise SceneError(key, f"{value!r} is beyond the float32 range the renderers use "
                              f"(|x| <= {MAX_MAGNITUDE:g})")
    if low is not None and (x <= low if low_open else x < low):
        raise SceneError(key, f"must be {'>' if low_open else '>='} {low}, got {value!r}")
    if low == 0.0 and low_open and x < MIN_POSITIVE:
        raise SceneError(key, f"{value!r} is too small for float32 (at least {MIN_POSITIVE:g})")
    if high is not None and x > high:
        raise SceneError(key, f"must be <= {high}, got {value!r}")
    return x


def unit(v: np.ndarray, key: str) -> np.ndarray:
    length = float(np.linalg.norm(v))
    if length == 0.0 or not math.isfinite(length):
        raise SceneError(key, "must be a non-zero direction")
    out = v / length
    out.setflags(write=False)
    return out


def _frozen(arr: np.ndarray) -> np.ndarray:
    arr.setflags(write=False)
    return arr


# ---------------------------------------------------------------------------------------------
# Materials and lights
# ---------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Material:
    """Phong material.  Colours are linear RGB (3,) float64.

    The ray tracer's colour is `local * (1 - reflectivity - transparency) + reflectivity *
    reflected + transparency * refracted`, so `reflectivity + transparency` must not exceed 1.

    `emission` is the radiance the surface emits itself, the same from both faces and in every
    direction (a Lambertian emitter): it makes an object an area light for the path tracer and
    radiosity (`raytrace.pathtrace`, `raytrace.radiosity`).  The shadow-volume renderer, the
    masks and Whitted ignore it: they light only with `Scene.lights`.
    """

    ambient: np.ndarray = field(default_factory=lambda: vec([0.1, 0.1, 0.1], "ambient"))
    diffuse: np.ndarray = field(default_factory=lambda: vec([0.8, 0.8, 0.8], "diffuse"))
    specular: np.ndarray = field(default_factory=lambda: vec([0.2, 0.2, 0.2], "specular"))
    shininess: float = 32.0
    reflectivity: float = 0.0
    transparency: float = 0.0
    ior: float = 1.5
    emission: np.ndarray = field(default_factory=lambda: vec([0.0, 0.0, 0.0], "emission"))

    def __post_init__(self):
        for name in ("ambient", "diffuse", "specular", "emission"):
            v = vec(getattr(self, name), name)
            if np.any(v < 0):
                raise SceneError(name, f"colour components must be >= 0, got {v.tolist()}")
            object.__setattr__(self, name, v)
        object.__setattr__(self, "shininess", num(self.shininess, "shininess", low=0.0))
        object.__setattr__(self, "reflectivity",
                           num(self.reflectivity, "reflectivity", low=0.0, high=1.0))
        object.__setattr__(self, "transparency",
                           num(self.transparency, "transparency", low=0.0, high=1.0))
        object.__setattr__(self, "ior", num(self.ior, "ior", low=0.0, low_open=True))
        if self.reflectivity + self.transparency > 1.0 + 1e-12:
            raise SceneError("reflectivity", "reflectivity + transparency must be <= 1")


class _Emitter:
    """What every light has: a colour (linear RGB, (3,) float64) times an intensity."""

    def _check_colour(self) -> None:
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

    def __post_init__(self):
        object.__setattr__(self, "position", vec(self.position, "position"))
        self._check_colour()


@dataclass(frozen=True, eq=False)
class DirectionalLight(_Emitter):
    """`direction` is the direction the light travels (unit length after construction)."""

    direction: np.ndarray
    color: np.ndarray = field(default_factory=lambda: vec([1, 1, 1], "color"))
    intensity: float = 1.0

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
              `primitives.default_plane_axes`), "disk" (centre, normal, radius) or "sphere"
              (centre, radius)
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
    positions: np.ndarray = field(init=False, repr=False)
    weights: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        from shadowvol import arealights
        from shadowvol.primitives import (
            default_plane_axes,  # (primitives imports this module)
        )

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
        object.__setattr__(self, "positions", _frozen(np.ascontiguousarray(points)))
        object.__setattr__(self, "weights", _frozen(np.full(n, 1.0 / n)))

    @functools.cached_property
    def hard(self) -> tuple[PointLight | AreaSample, ...]:
        """The N sample lights, in sample order, each with intensity * weight: AreaSample for a
        rect or disk, PointLight for a sphere."""
        if self.shape == "sphere":
            return tuple(PointLight(p, self.color, self.intensity * w)
                         for p, w in zip(self.positions, self.weights))
        return tuple(AreaSample(p, self.normal, 90.0, self.color, self.intensity * w)
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


# ---------------------------------------------------------------------------------------------
# Geometry
# ---------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Sphere:
    """Exact sphere in world space (for the ray tracer's images)."""

    center: np.ndarray
    radius: float

    def __post_init__(self):
        object.__setattr__(self, "center", vec(self.center, "center"))
        object.__setattr__(self, "radius", num(self.radius, "radius", low=0.0, low_open=True))


@dataclass(frozen=True, eq=False)
class Parallelogram:
    """Exact finite plane in world space: points origin + s*edge_u + t*edge_v, s, t in [0, 1].

    A rectangle under any affine transform stays a parallelogram, so this is the analytic form
    of the scene's `plane` primitive.  `normal` is unit length: cross(edge_u, edge_v) normalised.
    """

    origin: np.ndarray
    edge_u: np.ndarray
    edge_v: np.ndarray

    def __post_init__(self):
        for name in ("origin", "edge_u", "edge_v"):
            object.__setattr__(self, name, vec(getattr(self, name), name))
        if np.linalg.norm(np.cross(self.edge_u, self.edge_v)) == 0.0:
            raise SceneError("size", "the plane has zero area")

    @property
    def normal(self) -> np.ndarray:
        return unit(np.cross(self.edge_u, self.edge_v), "normal")


Analytic = Sphere | Parallelogram


@dataclass(frozen=True, eq=False)
class Object:
    """One object: world-space triangles and a material.

    vertices : (n, 3) float64, read-only, world space (as loaded: duplicated seam vertices stay)
    faces    : (m, 3) int64, read-only, indices into `vertices`; winding is not trusted by the
               renderers (surfaces are two-sided)
    analytic : the exact shape the triangles tessellate, or None for meshes
    """

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    material: Material = field(default_factory=Material)
    analytic: Analytic | None = None

    def __post_init__(self):
        v = np.array(self.vertices, dtype=np.float64)
        f = np.array(self.faces)
        if v.ndim != 2 or v.shape[1] != 3:
            raise SceneError("vertices", f"expected an (n, 3) array, got shape {v.shape}")
        if f.size == 0:
            f = f.reshape(0, 3)
        if f.ndim != 2 or f.shape[1] != 3:
            raise SceneError("faces", f"expected an (m, 3) array of triangles, got shape {f.shape}")
        if f.shape[0] == 0:
            raise SceneError("faces", "the mesh has no triangles")
        if not np.issubdtype(f.dtype, np.integer):
            raise SceneError("faces", f"indices must be integers, got {f.dtype}")
        if f.min() < 0 or f.max() >= len(v):
            raise SceneError("faces", f"index out of range 0..{len(v) - 1}")
        bad = ~np.isfinite(v).all(axis=1)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise SceneError("vertices", f"{int(bad.sum())} non-finite vertices "
                                         f"(first: vertex {i} = {v[i].tolist()})")
        far = (np.abs(v) > MAX_MAGNITUDE).any(axis=1)
        if far.any():
            i = int(np.flatnonzero(far)[0])
            raise SceneError("vertices", f"{int(far.sum())} vertices beyond the float32 range "
                                         f"the renderers use (|x| <= {MAX_MAGNITUDE:g}; first: "
                                         f"vertex {i} = {v[i].tolist()})")
        object.__setattr__(self, "vertices", _frozen(v))
        object.__setattr__(self, "faces", _frozen(f.astype(np.int64)))

    @property
    def triangles(self) -> np.ndarray:
        """(m, 3, 3) float64: the corner positions of every triangle."""
        return self.vertices[self.faces]


@dataclass(frozen=True, eq=False)
class Camera:
    """Look-at camera, OpenGL style (looks down its -z axis); see CONVENTIONS.md."""

    eye: np.ndarray
    target: np.ndarray
    up: np.ndarray = field(default_factory=lambda: vec([0, 1, 0], "up"))
    fov_y: float = 45.0
    near: float = 0.05

    def __post_init__(self):
        for name in ("eye", "target", "up"):
            object.__setattr__(self, name, vec(getattr(self, name), name))
        object.__setattr__(self, "fov_y", num(self.fov_y, "fov_y", low=0.0, high=179.0,
                                              low_open=True))
        object.__setattr__(self, "near", num(self.near, "near", low=0.0, low_open=True))
        view = self.target - self.eye
        if np.linalg.norm(view) == 0.0:
            raise SceneError("target", "eye and target are the same point")
        if np.linalg.norm(self.up) == 0.0:
            raise SceneError("up", "up is the zero vector")
        sin = np.linalg.norm(np.cross(view, self.up)) / (np.linalg.norm(view) *
                                                         np.linalg.norm(self.up))
        if sin < PARALLEL_TOLERANCE:
            raise SceneError("up", "up is parallel to the view direction (target - eye)")


@dataclass(frozen=True, eq=False)
class Scene:
    """The whole scene.  Build it in code (see `shadowvol.primitives`) or load it from a file
    (`shadowvol.scenefile.load_scene`); change it with `dataclasses.replace`."""

    camera: Camera
    objects: tuple[Object, ...]
    lights: tuple[Light, ...]
    width: int = 640
    height: int = 480
    ambient: np.ndarray = field(default_factory=lambda: vec([1, 1, 1], "ambient"))
    background: np.ndarray = field(default_factory=lambda: vec([0.05, 0.05, 0.08], "background"))
    max_depth: int = 4
    name: str = "scene"

    def __post_init__(self):
        object.__setattr__(self, "objects", tuple(self.objects))
        object.__setattr__(self, "lights", tuple(self.lights))
        for key in ("width", "height"):
            n = getattr(self, key)
            if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n <= 0:
                raise SceneError(f"image.{key}", f"must be a positive whole number, got {n!r}")
        if self.width * self.height > MAX_IMAGE_PIXELS:
            raise SceneError("image", f"{self.width}x{self.height} is more than "
                                      f"{MAX_IMAGE_PIXELS} pixels")
        md = self.max_depth
        if isinstance(md, bool) or not isinstance(md, (int, np.integer)) or md < 0:
            raise SceneError("render.max_depth", f"must be a whole number >= 0, got {md!r}")
        object.__setattr__(self, "ambient", vec(self.ambient, "ambient"))
        object.__setattr__(self, "background", vec(self.background, "image.background"))
        for i, light in enumerate(self.lights):
            if not isinstance(light, (PointLight, DirectionalLight, SpotLight, AreaLight)):
                raise SceneError(f"lights[{i}]", f"not a light: {type(light).__name__}")
        if not self.objects:
            raise SceneError("objects", "the scene has no objects")

    @property
    def aspect(self) -> float:
        return self.width / self.height

    def triangles(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """All objects' triangles as one soup.

        Returns vertices (N, 3) float64, faces (M, 3) int64 and object_ids (M,) int32 (the index
        into `objects` of each triangle).
        """
        offsets = np.cumsum([0] + [len(o.vertices) for o in self.objects])
        vertices = np.concatenate([o.vertices for o in self.objects])
        faces = np.concatenate([o.faces + off for o, off in zip(self.objects, offsets)])
        ids = np.concatenate([np.full(len(o.faces), i, np.int32)
                              for i, o in enumerate(self.objects)])
        return vertices, faces, ids

    @functools.cached_property
    def extent(self) -> float:
        """Diagonal of the bounding box of all geometry and the eye: the scene's length scale.
        Computed once per scene (it walks every vertex; the scene is immutable)."""
        pts = np.concatenate([o.vertices for o in self.objects] + [self.camera.eye[None]])
        return float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0))) or 1.0

    def replace(self, **changes) -> "Scene":
        return dataclasses.replace(self, **changes)
