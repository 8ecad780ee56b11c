"""The scene model: the single, immutable input of both renderers.

Everything here is plain data (frozen dataclasses holding read-only numpy arrays) and has no GL
import, so the ray tracer can use it without a context.  Geometry is stored in world space, already
transformed, as triangles; an object made from a primitive also keeps its exact analytic form
(`Sphere`, `Parallelogram`) for the ray tracer's images.  Mask comparisons always use the triangles
(see CONVENTIONS.md: "Everything that casts or receives a shadow in a mask comparison is triangles").

Constructors validate their input and raise `SceneError` naming the key and the problem; the file
loader (`shadowvol.scenefile`) adds the file name.  Colours are linear RGB; images are encoded to
sRGB only when written.  The lights are `shadowvol.lights`, the value checks and `SceneError`
`shadowvol.checks`; both are named here too.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
from dataclasses import dataclass, field

import numpy as np

# the lights and the value checks live in their own modules; `shadowvol.scene.AreaLight`,
# `shadowvol.scene.SceneError` and the rest stay the model's public names
from shadowvol.checks import (  # noqa: F401 (re-exported)
    MAX_MAGNITUDE,
    SceneError,
    flag,
    frozen,
    is_number,
    num,
    reject_unknown_keys,
    rigid_matrix,
    shorten,
    similarity_matrix,
    unit,
    vec,
)
from shadowvol.lights import (  # noqa: F401 (re-exported)
    AreaLight,
    AreaSample,
    DirectionalLight,
    Light,
    PointLight,
    SpotLight,
    emission_cosine,
    hard_lights,
    light_samples,
)
from shadowvol.textures import Texture, vertex_colours, vertex_uv

# Geometric tolerances of the scene model itself (renderer tolerances live with each renderer).
PARALLEL_TOLERANCE = 1e-9  # |sin| of the angle below which `up` counts as parallel to the view
# An absolute cap on the pixels of an image, 16384 x 16384 (the largest frame llvmpipe makes):
# below it the memory budget decides what fits (`shadowvol.memory`); above it an image is
# refused as a limit whatever the machine's memory (a typo such as 1e6 x 1e6 among them).
MAX_IMAGE_PIXELS = 1 << 28


# ---------------------------------------------------------------------------------------------
# Materials
# ---------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Material:
    """Phong material.  Colours are linear RGB (3,) float64.

    The ray tracer's colour is `local * (1 - reflectivity - transparency) + reflectivity *
    reflected + transparency * refracted`, so `reflectivity + transparency` must not exceed 1.

    `emission` is the radiance the surface emits itself, the same from both faces and in every
    direction (a Lambertian emitter): it makes an object an area light for the path tracer and
    radiosity (`raytrace.outlook.path.pathtrace`, `raytrace.outlook.radiosity`).  The shadow-volume
    renderer, the masks and Whitted ignore it: they light only with `Scene.lights`.

    `roughness` in [0, 1] blurs Whitted's reflection into a glossy lobe around the mirror
    direction (`raytrace.outlook.sampling.glossy`); 0 is the exact mirror.  The rasterizer, the path
    tracer and radiosity ignore it.

    `texture`: a base-colour `Texture`, sampled at the object's UVs; with the object's vertex
    colours it multiplies `ambient` and `diffuse` (docs/CONVENTIONS.md, "Textures").
    """

    ambient: np.ndarray = field(default_factory=lambda: vec([0.1, 0.1, 0.1], "ambient"))
    diffuse: np.ndarray = field(default_factory=lambda: vec([0.8, 0.8, 0.8], "diffuse"))
    specular: np.ndarray = field(default_factory=lambda: vec([0.2, 0.2, 0.2], "specular"))
    shininess: float = 32.0
    reflectivity: float = 0.0
    transparency: float = 0.0
    ior: float = 1.5
    emission: np.ndarray = field(default_factory=lambda: vec([0.0, 0.0, 0.0], "emission"))
    roughness: float = 0.0
    texture: Texture | None = None

    def __post_init__(self):
        if self.texture is not None and not isinstance(self.texture, Texture):
            raise SceneError("texture", f"not a Texture: {type(self.texture).__name__}")
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
        object.__setattr__(self, "roughness",
                           num(self.roughness, "roughness", low=0.0, high=1.0))
        if self.reflectivity + self.transparency > 1.0 + 1e-12:
            raise SceneError("reflectivity", "reflectivity + transparency must be <= 1")

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
    cast_shadows    : False: it blocks no light (no shadow volume, no shadow ray); still seen
    receive_shadows : False: it is lit as if nothing blocked its lights (docs/CONVENTIONS.md,
                      "Shadow switches")
    uv       : (n, 2) float64, read-only, per-vertex texture coordinates (glTF's convention:
               v down), or None; needed by a `material.texture`
    colors   : (n, 3) float64, read-only, per-vertex linear RGB colours, or None (all 1)
    category : its class name for the datasets (None: its name; `BACKGROUND` is the stage,
               never annotated nor a model: docs/formats.md)
    pose     : (4, 4) float64, read-only, model to world, a similarity (`vertices` = pose
               applied to the model's vertices); None: the identity (the model is the world)
    model    : the key of the model it is an instance of (the scene file sets the mesh file
               and its scale); None: its own model (`model_key`)
    """

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    material: Material = field(default_factory=Material)
    analytic: Analytic | None = None
    cast_shadows: bool = True
    receive_shadows: bool = True
    uv: np.ndarray | None = None
    colors: np.ndarray | None = None
    category: str | None = None
    pose: np.ndarray | None = None
    model: str | None = None

    def __post_init__(self):
        for key in ("cast_shadows", "receive_shadows"):
            object.__setattr__(self, key, flag(getattr(self, key), key))
        for key in ("category", "model"):
            value = getattr(self, key)
            if value is not None and (not isinstance(value, str) or not value):
                raise SceneError(key, f"expected a non-empty string, got {shorten(value)}")
        if self.pose is not None:
            object.__setattr__(self, "pose", similarity_matrix(self.pose, "pose")[0])
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
        object.__setattr__(self, "vertices", frozen(v))
        object.__setattr__(self, "faces", frozen(f.astype(np.int64)))
        object.__setattr__(self, "uv", vertex_uv(self.uv, len(v)))
        object.__setattr__(self, "colors", vertex_colours(self.colors, len(v)))
        if self.material.texture is not None and self.uv is None:
            raise SceneError("uv", "a textured material needs texture coordinates (uv)")

    @property
    def triangles(self) -> np.ndarray:
        """(m, 3, 3) float64: the corner positions of every triangle."""
        return self.vertices[self.faces]

    @property
    def label(self) -> str:
        """Its class name: `category`, else its name."""
        return self.name if self.category is None else self.category

    @functools.cached_property
    def model_key(self) -> str:
        """The key of its model: `model`, else a hash of its own triangles and pose (so one
        object of one scene is one model wherever it is rendered)."""
        if self.model is not None:
            return self.model
        h = hashlib.sha256(np.ascontiguousarray(self.vertices).tobytes())
        h.update(np.ascontiguousarray(self.faces).tobytes())
        h.update(b"" if self.pose is None else self.pose.tobytes())
        return "sha256:" + h.hexdigest()

    def model_vertices(self) -> np.ndarray:
        """(n, 3) float64: the vertices in its model frame (the pose undone)."""
        if self.pose is None:
            return self.vertices
        scaled = self.pose[:3, :3]
        return np.linalg.solve(scaled, (self.vertices - self.pose[:3, 3]).T).T


BACKGROUND = "background"   # the category of the stage (docs/formats.md)


@dataclass(frozen=True, eq=False)
class Camera:
    """A pinhole camera, OpenGL style (looks down its -z axis); see CONVENTIONS.md.  Given in
    one of two forms, never both:

    * look-at: `eye`, `target`, `up` (default +y) and the vertical field of view `fov_y` in
      degrees (default 45): square pixels, the principal point at the image centre;
    * matrices: intrinsics `fx`, `fy`, `cx`, `cy` (pixels, the `K` every frame carries:
      u = fx X/Z + cx, v = fy Y/Z + cy in OpenCV camera axes, pixel (x, y) centred at
      (x + 0.5, y + 0.5)) and `camera_to_world` (4, 4), OpenGL camera axes (x right, y up,
      looking down -z) to world, rigid (`RIGID_TOLERANCE`), the matrix every frame carries.
      Both are used as given, and every frame writes them back unchanged.  `eye`, `target`
      (eye - the back axis) and `up` are then filled in from the matrix, and `fov_y` is None.
      The intrinsics are pixels of the image rendered: `Scene.replace` with a new size scales
      them with it.

    `aperture` (the lens radius, 0: a pinhole) and `focus_distance` (the eye-space depth of the
    plane in focus; None: the distance to `target`, which a matrix camera does not have) give
    Whitted's image depth of field (`raytrace.camera.sample_rays`).  The rasterizer, every
    mask, the path tracer and radiosity stay a pinhole.
    """

    eye: np.ndarray | None = None
    target: np.ndarray | None = None
    up: np.ndarray | None = None
    fov_y: float | None = None
    near: float = 0.05
    aperture: float = 0.0
    focus_distance: float | None = None
    fx: float | None = None
    fy: float | None = None
    cx: float | None = None
    cy: float | None = None
    camera_to_world: np.ndarray | None = None

    def __post_init__(self):
        object.__setattr__(self, "aperture", num(self.aperture, "aperture", low=0.0))
        if self.focus_distance is not None:
            object.__setattr__(self, "focus_distance", num(self.focus_distance,
                                                           "focus_distance", low=0.0,
                                                           low_open=True))
        object.__setattr__(self, "near", num(self.near, "near", low=0.0, low_open=True))
        if self.matrix_form:
            self._check_matrices()
        else:
            self._check_look_at()

    @property
    def matrix_form(self) -> bool:
        """Given by intrinsics and camera_to_world (some of those keys given), not look-at."""
        return any(getattr(self, k) is not None for k in MATRIX_CAMERA_KEYS)

    def _check_look_at(self) -> None:
        for name in ("eye", "target"):
            if getattr(self, name) is None:
                raise SceneError(name, "missing (a camera needs eye and target, or fx, fy, "
                                       "cx, cy and camera_to_world)")
        object.__setattr__(self, "up", [0, 1, 0] if self.up is None else self.up)
        for name in ("eye", "target", "up"):
            object.__setattr__(self, name, vec(getattr(self, name), name))
        object.__setattr__(self, "fov_y", num(45.0 if self.fov_y is None else self.fov_y,
                                              "fov_y", low=0.0, high=179.0, low_open=True))
        view = self.target - self.eye
        if np.linalg.norm(view) == 0.0:
            raise SceneError("target", "eye and target are the same point")
        if np.linalg.norm(self.up) == 0.0:
            raise SceneError("up", "up is the zero vector")
        sin = np.linalg.norm(np.cross(view, self.up)) / (np.linalg.norm(view) *
                                                         np.linalg.norm(self.up))
        if sin < PARALLEL_TOLERANCE:
            raise SceneError("up", "up is parallel to the view direction (target - eye)")

    def _check_matrices(self) -> None:
        for name in MATRIX_CAMERA_KEYS:
            if getattr(self, name) is None:
                raise SceneError(name, "missing: a camera given by intrinsics needs fx, fy, "
                                       "cx, cy and camera_to_world")
        for name in ("fx", "fy"):
            object.__setattr__(self, name, num(getattr(self, name), name, low=0.0,
                                               low_open=True))
        for name in ("cx", "cy"):
            object.__setattr__(self, name, num(getattr(self, name), name))
        m = rigid_matrix(self.camera_to_world, "camera_to_world")
        object.__setattr__(self, "camera_to_world", m)
        eye, up = frozen(m[:3, 3].copy()), frozen(m[:3, 1].copy())
        target = frozen(eye - m[:3, 2])
        # eye, target and up are the matrix's; given otherwise, they mix the two forms (a
        # `dataclasses.replace` of another field passes them back unchanged)
        for name, derived in (("eye", eye), ("target", target), ("up", up)):
            value = getattr(self, name)
            if value is not None and not np.array_equal(np.asarray(value, np.float64),
                                                        derived):
                raise SceneError(name, MIXED_FORMS)
        if self.fov_y is not None:
            raise SceneError("fov_y", MIXED_FORMS)
        if self.aperture > 0.0 and self.focus_distance is None:
            raise SceneError("focus_distance", "missing: a camera given by camera_to_world has "
                                               "no target to focus on when aperture > 0")
        object.__setattr__(self, "eye", eye)
        object.__setattr__(self, "target", target)
        object.__setattr__(self, "up", up)

    @property
    def focus(self) -> float:
        """The eye-space depth of the plane in focus: `focus_distance`, else |target - eye|."""
        if self.focus_distance is not None:
            return self.focus_distance
        return float(np.linalg.norm(self.target - self.eye))

    def translated(self, offset) -> "Camera":
        """The same camera moved by `offset` (3,) float64: eye (and target, or the matrix's
        translation) + offset, each rounded once; everything else as it is."""
        offset = np.asarray(offset, np.float64)
        if not self.matrix_form:
            return dataclasses.replace(self, eye=self.eye + offset, target=self.target + offset)
        m = self.camera_to_world.copy()
        m[:3, 3] += offset
        return dataclasses.replace(self, camera_to_world=m, eye=None, target=None, up=None)

    def scaled(self, sx: float, sy: float) -> "Camera":
        """For an image sx times as wide and sy times as tall: a matrix camera's intrinsics
        scaled with it (fx, cx by sx; fy, cy by sy); a look-at camera is unchanged."""
        if not self.matrix_form or (sx == 1.0 and sy == 1.0):
            return self
        return dataclasses.replace(self, fx=self.fx * sx, cx=self.cx * sx, fy=self.fy * sy,
                                   cy=self.cy * sy)


MATRIX_CAMERA_KEYS = ("fx", "fy", "cx", "cy", "camera_to_world")
LOOK_AT_CAMERA_KEYS = ("eye", "target", "up", "fov_y")
MIXED_FORMS = ("mixes the two camera forms: give eye, target, up, fov_y or fx, fy, cx, cy, "
               "camera_to_world, not both")


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

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels: what the camera's projection is of (`cameras.pinhole`)."""
        return self.width, self.height

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
        """`dataclasses.replace`, except that a new width or height scales the intrinsics of a
        matrix camera with the image (`Camera.scaled`), unless a camera is given too."""
        if "camera" not in changes and ("width" in changes or "height" in changes):
            changes["camera"] = self.camera.scaled(
                changes.get("width", self.width) / self.width,
                changes.get("height", self.height) / self.height)
        return dataclasses.replace(self, **changes)
