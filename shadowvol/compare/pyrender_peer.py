"""Bridge to pyrender: our scene as a pyrender.Scene and back, and pyrender's shadow-mapped masks.

pyrender is the peer the `compare` command measures against: it draws shadows with shadow maps
(spot and directional lights only; pyrender has NO point-light shadows, its PointLight raises
"Shadows not implemented for point lights"), so its masks show what shadow mapping gets wrong
(resolution, bias, PCF blur) next to the exact stencil shadows and the ray tracer.

pyrender is imported lazily, inside the functions, through `import_pyrender()`, which is the only place
that touches two compatibility problems of pyrender 0.1.45 (pinned in pyproject's `peer` extra):
- it uses `np.infty`, removed in NumPy 2: we add the alias (`np.infty = np.inf`) if it is missing,
  here and nowhere else;
- headless rendering needs `PYOPENGL_PLATFORM=egl` before PyOpenGL is first imported: we set it if
  it is not set already (an explicit `osmesa` is respected).
A third one is handled by `shadowvol.raster.platform.pyrender_context.offscreen`: pyrender's
`OffscreenRenderer.delete()` calls `eglTerminate` on the EGL display, which is shared by every EGL
user in the process (pyrender issue #223, "re-create OffscreenRenderer": EGL_BAD_DISPLAY), so it
would kill a moderngl context living beside it, and pyrender leaves its own context current.  We
tear the renderer down without terminating the display and make the caller's context current
again.

One more pyrender behaviour shows in its images and masks and is left as it is, because it is
part of what the comparison measures: its shadow pass culls back faces (by winding) even for
double-sided materials (renderer.py draws DEPTH_ONLY primitives with GL_CULL_FACE on), so an open
surface wound away from a light casts no shadow in pyrender.  Closed meshes are unaffected.

What the conversion keeps and what it approximates:
- geometry: exact (world-space triangles; pyrender gets one mesh node per object, identity pose,
  flat face normals, double-sided);
- camera: exact (pose = inverse view, yfov, znear, aspect; a camera given by matrices as
  pyrender's IntrinsicsCamera, whose projection is ours; no far plane in either);
- lights: type, pose, colour and cone exact (spot: outer cone = inner cone = `cone_angle`, the
  hardest edge pyrender allows).  Intensity is approximate: our lights have no distance fall-off,
  pyrender's point and spot lights fall off as 1/d^2, so pyrender's intensity is ours times
  d_ref^2, where d_ref is the area-weighted RMS distance from the light to the triangles'
  centroids (so brightness matches ours at a typical distance: nearer surfaces come out
  brighter, farther ones darker), divided by pyrender's diffuse factor (1 - 0.04)/pi;
- materials: Phong -> metallic-roughness: diffuse -> base colour, shininess s -> roughness
  (2/(s+2))^(1/4) (the Blinn-Phong/GGX width match), ambient * scene ambient -> emissive, metallic
  0.  The specular colour, reflectivity, transparency and ior have no counterpart and are lost
  (mirrors and glass render as their diffuse colour).  Back from pyrender: base colour (or the
  spec-gloss diffuse) -> diffuse, emissive^2 + base colour * the scene's ambient light -> ambient,
  the metallic-roughness F0 -> specular, roughness -> shininess; textures are ignored.
"""

from __future__ import annotations

import math
import os
import re

import numpy as np

from shadowvol.errors import require
from shadowvol.raster.platform import pyrender_context
from shadowvol.scene import (
    AreaLight,
    Camera,
    DirectionalLight,
    Material,
    Object,
    PointLight,
    Scene,
    SpotLight,
)

PBR_MIN_ROUGHNESS = 0.04            # pyrender mesh.frag `min_roughness`: also the dielectric F0
PBR_DIFFUSE = (1.0 - PBR_MIN_ROUGHNESS) / math.pi   # pyrender's Lambert factor per unit intensity
PYRENDER_GAMMA = 2.2                 # pyrender encodes its colour output as pow(c, 1/2.2)
MIN_SHININESS = 1.0                  # roughness 1 would map to a Phong exponent of 0 (flat)
# A pixel is shadow-mapped when its shadowed brightness (linear) is below this fraction of its
# unshadowed brightness: pyrender's PCF gives fractional shadow at edges; half-way decides.
SHADOW_RATIO = 0.5
# A light closer to the geometry than this fraction of the scene's extent is placed at this
# distance for the mask renders' exposure (keeps the exposure finite for a light on a surface).
MIN_LIGHT_DISTANCE = 1e-3


# ---------------------------------------------------------------------------------------------
# Importing pyrender, and its EGL context
# ---------------------------------------------------------------------------------------------

def import_pyrender():
    """Import pyrender with its NumPy 2 and headless shims (see the module docstring); without
    the [peer] extra, MissingExtra (exit status 2) naming the pip command."""
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    if not hasattr(np, "infty"):
        np.infty = np.inf        # pyrender 0.1.45 mesh.py uses np.infty (gone in NumPy 2)
    return require("pyrender", "pyrender's shadow maps (compare --pyrender)", extra="peer")


def _offscreen(width: int, height: int):
    """A pyrender OffscreenRenderer that leaves the process's EGL state as it found it."""
    return pyrender_context.offscreen(import_pyrender(), width, height)


# ---------------------------------------------------------------------------------------------
# Poses and conversions of single parts
# ---------------------------------------------------------------------------------------------

def camera_pose(camera: Camera) -> np.ndarray:
    """(4, 4) float64 camera-to-world matrix (the inverse of the view matrix): columns right, up,
    back (the camera looks down its -z), eye; a camera given by matrices: its own."""
    if camera.matrix_form:
        return camera.camera_to_world.copy()
    f = camera.target - camera.eye
    f = f / np.linalg.norm(f)
    s = np.cross(f, camera.up)
    s = s / np.linalg.norm(s)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = s, np.cross(s, f), -f, camera.eye
    return pose


def _pr_camera(scene: Scene):
    """pyrender's camera for ours, without a far plane: an IntrinsicsCamera for a camera given
    by matrices (pyrender's projection from fx, fy, cx, cy is ours, `raster.projection`), else
    a PerspectiveCamera of fov_y and the image's aspect ratio."""
    pyrender = import_pyrender()
    cam = scene.camera
    if cam.matrix_form:
        camera = pyrender.IntrinsicsCamera(cam.fx, cam.fy, cam.cx, cam.cy, znear=cam.near)
        # pyrender 0.1.45's Camera.zfar setter refuses None, though IntrinsicsCamera's
        # projection takes None as the infinite far plane (as PerspectiveCamera's does)
        camera._zfar = None
        return camera
    return pyrender.PerspectiveCamera(yfov=math.radians(cam.fov_y), znear=cam.near, zfar=None,
                                      aspectRatio=scene.aspect)


def _pointing_pose(position: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """(4, 4) pose at `position` whose -z axis is the unit `direction` (pyrender lights shine
    along their -z)."""
    z = -direction
    a = np.array([0.0, 1.0, 0.0]) if abs(z[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(a, z)
    x = x / np.linalg.norm(x)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = x, np.cross(z, x), z, position
    return pose


def _falloff_scale(position: np.ndarray, triangles: np.ndarray) -> float:
    """d_ref^2: the area-weighted mean squared distance from `position` to the triangles'
    centroids.  triangles : (m, 3, 3) float64.  1.0 when every triangle is degenerate."""
    centroids = triangles.mean(axis=1)
    areas = 0.5 * np.linalg.norm(np.cross(triangles[:, 1] - triangles[:, 0],
                                          triangles[:, 2] - triangles[:, 0]), axis=1)
    if not areas.sum() > 0:
        return 1.0
    return float(np.sum(areas * np.sum((centroids - position) ** 2, axis=1)) / areas.sum())


def _roughness(shininess: float) -> float:
    return (2.0 / (max(shininess, MIN_SHININESS) + 2.0)) ** 0.25


def _shininess(roughness: float) -> float:
    r = min(max(roughness, PBR_MIN_ROUGHNESS), 1.0)
    return max(2.0 / r ** 4 - 2.0, MIN_SHININESS)


def _pr_material(material: Material, scene_ambient: np.ndarray, name: str):
    pyrender = import_pyrender()
    # pyrender's mesh.frag adds `emissive * material.emissive_factor` with
    # emissive = emissive_factor: the factor counts squared, hence the square root.
    emissive = np.sqrt(np.clip(material.ambient * scene_ambient, 0.0, 1.0))
    return pyrender.MetallicRoughnessMaterial(
        name=name, baseColorFactor=[*np.clip(material.diffuse, 0.0, 1.0), 1.0],
        metallicFactor=0.0, roughnessFactor=_roughness(material.shininess),
        emissiveFactor=emissive, doubleSided=True)


def _our_material(material, ambient_light: np.ndarray) -> Material:
    pyrender = import_pyrender()
    emissive = np.zeros(3)
    if material is not None and material.emissiveFactor is not None:
        emissive = np.asarray(material.emissiveFactor, dtype=np.float64)[:3]
    if isinstance(material, pyrender.material.SpecularGlossinessMaterial):
        diffuse = np.asarray(material.diffuseFactor, dtype=np.float64)[:3]
        specular = np.asarray(material.specularFactor, dtype=np.float64)[:3]
        shininess = _shininess(1.0 - float(material.glossinessFactor))
    else:
        base = (np.asarray(material.baseColorFactor, dtype=np.float64)[:3]
                if material is not None else np.ones(3))
        metallic = float(material.metallicFactor) if material is not None else 1.0
        roughness = float(material.roughnessFactor) if material is not None else 1.0
        diffuse = base * (1.0 - metallic)
        specular = PBR_MIN_ROUGHNESS * (1.0 - metallic) + base * metallic
        shininess = _shininess(roughness)
    return Material(ambient=emissive ** 2 + diffuse * ambient_light, diffuse=diffuse,
                    specular=specular, shininess=shininess)


def _node_key(pr_scene, node) -> tuple:
    """Sort key for nodes: by name, 'light2' before 'light10', unnamed (None) last; ties (equal
    or missing names) by world pose, so the order never depends on pyrender's node set."""
    name = node.name
    pose = tuple(np.asarray(pr_scene.get_pose(node), dtype=np.float64).ravel())
    if name is None:
        return (1, (), pose)
    return (0, tuple((0, int(t), "") if t.isdigit() else (1, 0, t)
                     for t in re.split(r"(\d+)", name)), pose)


# ---------------------------------------------------------------------------------------------
# Our scene -> pyrender
# ---------------------------------------------------------------------------------------------

def to_pyrender(scene: Scene):
    """Our Scene -> pyrender.Scene (see the module docstring for what is approximated).

    Mesh nodes are named after the objects, light nodes "light0", "light1", ... in the scene's
    order, the camera node "camera"; `from_pyrender` sorts by these names.
    """
    pyrender = import_pyrender()
    import trimesh

    pr = pyrender.Scene(bg_color=[*np.clip(scene.background, 0, 1) ** (1 / PYRENDER_GAMMA), 1.0],
                        ambient_light=np.zeros(3), name=scene.name)
    for obj in scene.objects:
        tm = trimesh.Trimesh(obj.vertices, obj.faces, process=False)
        mesh = pyrender.Mesh.from_trimesh(
            tm, material=_pr_material(obj.material, scene.ambient, obj.name), smooth=False)
        pr.add(mesh, name=obj.name)
    pr.add(_pr_camera(scene), pose=camera_pose(scene.camera), name="camera")
    vertices, faces, _ = scene.triangles()
    for i, light in enumerate(scene.lights):
        pr_light, pose = _pr_light(light, vertices[faces])
        pr.add(pr_light, name=f"light{i}", pose=pose)
    return pr


def _pr_light(light, triangles: np.ndarray, intensity: float | None = None):
    """(pyrender light, pose) for one of our lights; `intensity` overrides the conversion.
    triangles : (m, 3, 3) the scene's geometry (for the fall-off reference distance)."""
    if isinstance(light, AreaLight):
        raise ValueError(f"pyrender has no area lights (a {light.shape} light here): compare "
                         "with pyrender only scenes of point, spot and directional lights")
    pyrender = import_pyrender()
    if isinstance(light, DirectionalLight):
        value = light.intensity / PBR_DIFFUSE if intensity is None else intensity
        return (pyrender.DirectionalLight(color=light.color, intensity=value),
                _pointing_pose(np.zeros(3), light.direction))
    if intensity is None:
        intensity = light.intensity * _falloff_scale(light.position, triangles) / PBR_DIFFUSE
    if isinstance(light, SpotLight):
        cone = math.radians(light.cone_angle)
        return (pyrender.SpotLight(color=light.color, intensity=intensity,
                                   innerConeAngle=cone, outerConeAngle=cone),
                _pointing_pose(light.position, light.direction))
    pose = np.eye(4)
    pose[:3, 3] = light.position
    return pyrender.PointLight(color=light.color, intensity=intensity), pose


# ---------------------------------------------------------------------------------------------
# pyrender -> our scene
# ---------------------------------------------------------------------------------------------

def from_pyrender(pr_scene, width: int, height: int, name: str | None = None) -> Scene:
    """A pyrender.Scene -> our Scene of `width` x `height` pixels.

    - Every mesh node's triangle primitives (mode 4), with the node's world pose (parents
      included) and each instance pose, become one Object per primitive, named after the node
      (suffixed ".k" when the mesh has several primitives).  Points and lines have no area, cast
      and receive no shadow, and are left out.
    - The main camera node must hold a PerspectiveCamera, whose aspect ratio, if set, must
      equal width / height, or an IntrinsicsCamera, which becomes a camera given by matrices
      (fx, fy, cx, cy and the node's pose as camera_to_world, used as they are).  zfar is
      dropped (we have no far plane).
    - Directional, spot and point lights, sorted by node name ("light2" before "light10",
      unnamed last; equal names by pose).  Mesh nodes are sorted the same way.  Spot: cone_angle = the OUTER cone angle (the inner one's falloff is lost).
    - Materials and intensities: see the module docstring.  The scene's ambient light goes into
      each material's ambient; our scene ambient is white.
    """
    pyrender = import_pyrender()
    ambient_light = np.asarray(pr_scene.ambient_light, dtype=np.float64)[:3]
    objects = []
    for node in sorted(pr_scene.mesh_nodes, key=lambda n: _node_key(pr_scene, n)):
        pose = pr_scene.get_pose(node)
        prims = node.mesh.primitives
        for k, prim in enumerate(prims):
            if prim.mode != pyrender.constants.GLTF.TRIANGLES:
                continue
            positions = np.asarray(prim.positions, dtype=np.float64)
            faces = (np.asarray(prim.indices, dtype=np.int64).reshape(-1, 3)
                     if prim.indices is not None else
                     np.arange(len(positions), dtype=np.int64).reshape(-1, 3))
            instances = prim.poses if prim.poses is not None else np.eye(4)[None]
            homog = np.concatenate([positions, np.ones((len(positions), 1))], axis=1)
            verts = np.concatenate([(homog @ (pose @ inst).T)[:, :3] for inst in instances])
            faces = np.concatenate([faces + j * len(positions) for j in range(len(instances))])
            base = node.name or node.mesh.name or f"mesh{len(objects)}"
            objects.append(Object(base if len(prims) == 1 else f"{base}.{k}", verts, faces,
                                  _our_material(prim.material, ambient_light)))

    cam_node = pr_scene.main_camera_node
    if cam_node is None:
        raise ValueError("the pyrender scene has no camera")
    cam = cam_node.camera
    pose = pr_scene.get_pose(cam_node)
    if isinstance(cam, pyrender.IntrinsicsCamera):
        camera = Camera(fx=cam.fx, fy=cam.fy, cx=cam.cx, cy=cam.cy, camera_to_world=pose,
                        near=cam.znear)
    else:
        if not isinstance(cam, pyrender.PerspectiveCamera):
            raise ValueError(f"only perspective and intrinsics cameras convert, got "
                             f"{type(cam).__name__}")
        if cam.aspectRatio is not None and not math.isclose(cam.aspectRatio, width / height,
                                                            rel_tol=1e-6):
            raise ValueError(f"the camera's aspect ratio {cam.aspectRatio} differs from "
                             f"width / height = {width}/{height}")
        eye = pose[:3, 3]
        camera = Camera(eye=eye, target=eye - pose[:3, 2], up=pose[:3, 1],
                        fov_y=math.degrees(cam.yfov), near=cam.znear)

    triangles = (np.concatenate([o.triangles for o in objects]) if objects
                 else np.zeros((0, 3, 3)))
    lights = []
    for node in sorted(pr_scene.light_nodes, key=lambda n: _node_key(pr_scene, n)):
        light, pose = node.light, pr_scene.get_pose(node)
        position, direction = pose[:3, 3], -pose[:3, 2]
        if isinstance(light, pyrender.DirectionalLight):
            lights.append(DirectionalLight(direction, light.color,
                                           light.intensity * PBR_DIFFUSE))
            continue
        intensity = light.intensity * PBR_DIFFUSE / _falloff_scale(position, triangles)
        if isinstance(light, pyrender.SpotLight):
            lights.append(SpotLight(position, direction, math.degrees(light.outerConeAngle),
                                    light.color, intensity))
        else:
            lights.append(PointLight(position, light.color, intensity))
    background = np.clip(np.asarray(pr_scene.bg_color, dtype=np.float64)[:3], 0, 1)
    return Scene(camera=camera, objects=objects, lights=lights, width=width, height=height,
                 background=background ** PYRENDER_GAMMA,
                 name=name or pr_scene.name or "pyrender")


# ---------------------------------------------------------------------------------------------
# Rendering
# ---------------------------------------------------------------------------------------------

def _flags(shadows: bool):
    pyrender = import_pyrender()
    flags = pyrender.RenderFlags.NONE
    if shadows:
        flags |= pyrender.RenderFlags.SHADOWS_DIRECTIONAL | pyrender.RenderFlags.SHADOWS_SPOT
    return flags


def render_pyrender(scene: Scene, shadows: bool = True) -> np.ndarray:
    """pyrender's image of our scene: (H, W, 3) uint8, row 0 at the top.

    Encoded with pyrender's pow(c, 1/2.2), close to (not exactly) sRGB; 4x multisampled (pyrender
    always renders into a multisample buffer).  `shadows`: shadow maps for spot and directional
    lights; point lights never cast shadows in pyrender.
    """
    pr = to_pyrender(scene)
    with _offscreen(scene.width, scene.height) as r:
        color, _ = r.render(pr, flags=_flags(shadows))
    return np.ascontiguousarray(color[..., :3])


def maskable_lights(scene: Scene) -> tuple[int, ...]:
    """Indices of the lights pyrender can shadow (spot and directional; not point lights)."""
    return tuple(i for i, l in enumerate(scene.lights)
                 if isinstance(l, (SpotLight, DirectionalLight)))


def _linear(encoded: np.ndarray) -> np.ndarray:
    return (encoded.astype(np.float64) / 255.0) ** PYRENDER_GAMMA


def pyrender_shadow_masks(scene: Scene, lights=None) -> tuple[np.ndarray, np.ndarray]:
    """pyrender's shadow masks, as CONVENTIONS.md defines masks.

    lights : indices into scene.lights (default: all); a point light raises ValueError, since
             pyrender has no point-light shadows (use `maskable_lights`).
    Returns lit (len(lights), H, W) bool and coverage (H, W) bool (pyrender's depth > 0).

    How: every triangle gets its flat normal flipped to face the camera (the conventions' normal)
    and a white, fully rough material; with only light i and no ambient, three renders:
      A  unshadowed,  B  unshadowed with the normals flipped away,  S  shadow-mapped.
    pyrender clamps n . l to at least 0.001, so "A > B" (not "A > 0") is the test for
    n . l > 0: both get the same radiance and fall-off, only max(n.l, .001) against
    max(-n.l, .001) differs; outside a spot's cone both are 0, so the cone test comes free.
    The pixel is shadow-mapped when S < SHADOW_RATIO * A in linear brightness.  Pixels at
    silhouettes are multisampled blends, so masks are soft there (compare the interiors).
    The light's intensity is set so that n . l = 1 at the nearest geometry gives brightness 1,
    which keeps B far from saturating.
    """
    pyrender = import_pyrender()
    chosen = tuple(range(len(scene.lights))) if lights is None else tuple(lights)
    for i in chosen:
        if isinstance(scene.lights[i], PointLight):
            raise ValueError(f"lights[{i}] is a point light: pyrender has no point-light "
                             f"shadows, so it has no shadow mask")
    vertices, faces, _ = scene.triangles()
    tris = vertices[faces]                                           # (m, 3, 3)
    normals = _camera_facing_normals(tris, scene.camera.eye)

    white = pyrender.MetallicRoughnessMaterial(baseColorFactor=[1.0, 1.0, 1.0, 1.0],
                                               metallicFactor=0.0, roughnessFactor=1.0,
                                               doubleSided=True)

    def mesh(sign: float):
        prim = pyrender.Primitive(positions=tris.reshape(-1, 3).astype(np.float32),
                                  normals=np.repeat(sign * normals, 3, axis=0).astype(np.float32),
                                  material=white, mode=pyrender.constants.GLTF.TRIANGLES)
        return pyrender.Mesh([prim])

    pr = pyrender.Scene(bg_color=[0.0, 0.0, 0.0, 1.0], ambient_light=np.zeros(3))
    pr.add(_pr_camera(scene), pose=camera_pose(scene.camera))
    facing_mesh, away_mesh = mesh(1.0), mesh(-1.0)
    geometry = pr.add(facing_mesh)
    lit = np.zeros((len(chosen), scene.height, scene.width), bool)
    coverage = None
    extent = scene.extent
    with _offscreen(scene.width, scene.height) as r:
        for k, i in enumerate(chosen):
            light = scene.lights[i]
            pr_light, pose = _pr_light(light, tris, _intensity(light, tris, extent))
            light_node = pr.add(pr_light, pose=pose)
            if geometry.mesh is not facing_mesh:
                pr.remove_node(geometry)
                geometry = pr.add(facing_mesh)
            a, depth = r.render(pr, flags=_flags(False))
            s, _ = r.render(pr, flags=_flags(True))
            pr.remove_node(geometry)
            geometry = pr.add(away_mesh)
            b, _ = r.render(pr, flags=_flags(False))
            pr.remove_node(light_node)
            if coverage is None:
                coverage = depth > 0
            a, b, s = (x[..., :3].max(axis=-1) for x in (a, b, s))
            facing = a > b
            shadowed = _linear(s) < SHADOW_RATIO * _linear(a)
            lit[k] = coverage & facing & ~shadowed
    if coverage is None:     # no lights chosen: one render for the coverage alone
        with _offscreen(scene.width, scene.height) as r:
            coverage = r.render(pr, flags=_flags(False))[1] > 0
    return lit, coverage


def _camera_facing_normals(tris: np.ndarray, eye: np.ndarray) -> np.ndarray:
    """(m, 3) float64 unit flat normals of triangles (m, 3, 3), flipped to face `eye` (the
    conventions' normal; zero for a degenerate triangle)."""
    normals = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)
    toward = np.sign(np.einsum("ij,ij->i", normals, eye - tris[:, 0]))
    normals *= np.where(toward == 0, 1.0, toward)[:, None]           # face the camera
    return normals


def _intensity(light, tris: np.ndarray, extent: float) -> float:
    """The light's intensity for `pyrender_shadow_masks`: n . l = 1 at the nearest geometry
    gives brightness 1 (a directional light: everywhere)."""
    if isinstance(light, DirectionalLight):
        return 1.0 / PBR_DIFFUSE
    import trimesh

    nearest = trimesh.triangles.closest_point(
        tris, np.broadcast_to(light.position, (len(tris), 3)))
    d = max(float(np.min(np.linalg.norm(nearest - light.position, axis=1))),
            MIN_LIGHT_DISTANCE * extent)
    return d * d / PBR_DIFFUSE
