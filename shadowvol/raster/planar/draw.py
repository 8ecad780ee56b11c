"""Planar projected shadows drawn in GL (Blinn 1988), to put beside shadow volumes.

    with Renderer(scene) as r:
        planar = PlanarShadows(r).render()          # receiver: the largest plane object
        volumes = r.render()

A frame, per light (the same passes as a shadow-volume frame, with the volume count replaced):

1. depth + ambient for every triangle (`forward.depth_ambient`), once.
2. mark: the receiver's own triangles drawn again with depth test EQUAL (same vertex shader,
   same vertices: the depths tie bit for bit) write stencil PLANAR_RECEIVER where the receiver
   is the visible surface.
3. shadow: every other object's triangles, multiplied by `planar.projection_matrix` (squashed
   from the light onto the receiver's plane), drawn with colour and depth writes off where the
   stencil is PLANAR_RECEIVER, raising it to PLANAR_SHADOW.  So a pixel is shadowed at most once
   however many projected triangles overlap it (the "double blending" of the naive method),
   and never off the receiver's edge.  Fragments of caster points that are not between the
   light and the plane are discarded (anti-shadows; planar.frag, exact per fragment).  The
   depth test "nearer or equal" with a polygon offset toward the eye keeps the flattened
   geometry from z-fighting with the receiver it lies on (inside the marked pixels the
   projected point IS the visible receiver point, so the offset only has to cover rounding).
4. light: the light's Phong term added wherever the stencil is not PLANAR_SHADOW, writing its
   lit mask, exactly as the shadow-volume frame does where its count is 0.

So on the receiver the image and the lit mask are those of shadow volumes (and of the ray
tracer); everywhere else nothing is ever shadowed: no shadow on another object, no self-shadow.
That difference is the demo's point.  The renderer borrows a `Renderer`'s context, target and
scene programs and owns only its program and vertex array (call `release()`).
"""

from __future__ import annotations

from dataclasses import dataclass

import moderngl
import numpy as np

from shadowvol.raster.planar.matrix import plane_equation, projection_matrix
from shadowvol.raster import forward, glsl, passes
from shadowvol.raster.stencil import (
    planar_receiver_mark, planar_shadow_once, where_not_planar_shadow, zero_to_one_depth)
from shadowvol.raster.platform.context import make_current
from shadowvol.raster.projection import (
    NEARER,
    NEARER_OR_EQUAL,
    frame_view_projection,
    gl_matrix,
    in_frame,
    planes_in_frame,
)
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import Camera, Light, Parallelogram, Scene

# Polygon offset of the projected shadow (factor, units).  Depth is reversed (nearer = greater),
# so a POSITIVE offset moves the shadow toward the eye.  The flattened triangles are coplanar
# with the receiver and reach the same depths by another chain of float32 arithmetic; one
# slope unit plus one unit of the float depth's resolution covers that rounding.
POLYGON_OFFSET = (1.0, 1.0)

# A mesh named as receiver must be flat: every vertex within this distance of the plane of its
# first triangle, relative to the mesh's size (float64 loading and transforms leave ~1e-15).
PLANARITY_TOLERANCE = 1e-9


class ReceiverError(ValueError):
    """No receiving plane: no plane object in the scene, an unknown name, or a curved mesh."""


@dataclass(frozen=True, eq=False)
class PlanarResult:
    """One frame with planar projected shadows.

    image    : (H, W, 3) float32 linear RGB
    lit      : (L, H, W) bool, per light: covered, not in a projected shadow, n . l > 0, inside
               the spot cone (shadows only ever on the receiver)
    coverage : (H, W) bool
    receiver : int, index of the receiving object in scene.objects
    plane    : (4,) float64, the receiving plane P = (n, d)
    stencil  : (L, H, W) uint8 stencil after each light's shadow pass (0 elsewhere,
               PLANAR_RECEIVER on the receiver, PLANAR_SHADOW in its shadow), or None when not
               asked for
    """

    image: np.ndarray
    lit: np.ndarray
    coverage: np.ndarray
    receiver: int
    plane: np.ndarray
    stencil: np.ndarray | None

    def _repr_png_(self) -> bytes:
        """A notebook shows the frame as its image."""
        from shadowvol.display import frame_png
        return frame_png(self)


def receiver_index(scene: Scene, receiver: str | int | None = None) -> int:
    """The index of the receiving object: `receiver` by name or index, or (None) the plane
    object with the largest area.  Raises ReceiverError."""
    if receiver is None:
        areas = [(float(np.linalg.norm(np.cross(o.analytic.edge_u, o.analytic.edge_v))), i)
                 for i, o in enumerate(scene.objects) if isinstance(o.analytic, Parallelogram)]
        if not areas:
            raise ReceiverError(f"scene {scene.name!r} has no plane object to receive projected "
                                f"shadows; name a flat mesh as receiver")
        return max(areas)[1]
    if isinstance(receiver, (int, np.integer)) and not isinstance(receiver, bool):
        if not 0 <= receiver < len(scene.objects):
            raise ReceiverError(f"receiver index {receiver} is out of range "
                                f"0..{len(scene.objects) - 1}")
        return int(receiver)
    names = [o.name for o in scene.objects]
    if receiver not in names:
        raise ReceiverError(f"no object named {receiver!r} (objects: {', '.join(names)})")
    return names.index(receiver)


def receiver_plane(scene: Scene, index: int) -> np.ndarray:
    """(4,) float64 plane P = (n, d) of object `index`: its analytic plane, or the plane of a
    flat mesh's first non-degenerate triangle (ReceiverError when the mesh is not flat)."""
    obj = scene.objects[index]
    if isinstance(obj.analytic, Parallelogram):
        return plane_equation(obj.analytic.origin, obj.analytic.normal)
    tris = obj.triangles
    normals = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    lengths = np.linalg.norm(normals, axis=1)
    if not (lengths > 0).any():
        raise ReceiverError(f"object {obj.name!r} has only degenerate triangles")
    k = int(np.argmax(lengths > 0))
    P = plane_equation(tris[k, 0], normals[k])
    size = float(np.linalg.norm(np.ptp(obj.vertices, axis=0))) or 1.0
    off = np.abs(obj.vertices @ P[:3] + P[3]).max()
    if off > PLANARITY_TOLERANCE * size:
        raise ReceiverError(f"object {obj.name!r} is not flat (a vertex lies {off:.3g} off the "
                            f"plane of its first triangle): projected shadows need a plane")
    return P


class PlanarShadows:
    """Planar projected shadows in `renderer`'s context and target (see the module docstring).
    Call `release()` (or use as a context manager) before releasing the renderer."""

    def __init__(self, renderer: Renderer):
        self.renderer = renderer
        make_current(renderer.ctx)
        self.program = glsl.program(renderer.ctx, "planar.vert", "planar.frag")
        try:
            self.vao = renderer.ctx.vertex_array(
                self.program, [(renderer.geometry.positions, "3f", "in_position")])
        except BaseException:
            self.program.release()
            raise

    def render(self, receiver: str | int | None = None, *, camera: Camera | None = None,
               lights: tuple[Light, ...] | None = None, stencil: bool = False,
               shadows: bool = True) -> PlanarResult:
        """One frame with projected shadows on `receiver` (see `receiver_index`).
        `camera`/`lights` override the scene's; `stencil=True` also returns the stencil after
        each light's shadow pass; `shadows=False` skips the mark and shadow passes."""
        r = self.renderer
        scene = r.scene
        index = receiver_index(scene, receiver)
        plane = receiver_plane(scene, index)
        make_current(r.ctx)
        with zero_to_one_depth(r.gl):
            return self._render(scene, index, plane, camera, lights, stencil, shadows)

    def _render(self, scene, index, plane, camera, lights, stencil, shadows) -> PlanarResult:
        r = self.renderer
        camera = scene.camera if camera is None else camera
        lights = scene.lights if lights is None else tuple(lights)
        view_proj, origin = frame_view_projection(camera, scene.size)
        r.geometry.move_to(origin)
        passes.set_camera((r.programs.ambient, r.programs.phong), view_proj, camera, origin)
        forward.depth_ambient(r.pipeline)
        lit, counts = [], []
        for light in lights:
            r.target.clear_stencil()
            if shadows:
                self._mark_receiver(index)
                self._project_shadows(index, plane, light, view_proj)
            if stencil:
                counts.append(r.target.read_stencil().astype(np.uint8))
            forward.add_light(r.pipeline, light, where_not_planar_shadow)
            lit.append(r.target.read_lit())
        rgba = r.target.read_colour()
        h, w = scene.height, scene.width
        return PlanarResult(
            image=np.ascontiguousarray(rgba[..., :3]),
            lit=np.array(lit, bool).reshape(len(lights), h, w),
            coverage=rgba[..., 3] > 0.5, receiver=index, plane=plane,
            stencil=np.array(counts, np.uint8).reshape(len(lights), h, w) if stencil else None)

    def _mark_receiver(self, index: int) -> None:
        r = self.renderer
        rng = r.geometry.ranges[index]
        r.target.use(colour=False, depth=False)
        r.ctx.enable_only(moderngl.DEPTH_TEST)
        r.ctx.depth_func = "=="
        with planar_receiver_mark(r.gl):
            r.programs.ambient_vao.render(moderngl.TRIANGLES, vertices=3 * rng.count,
                                          first=3 * rng.first)
        r.ctx.depth_func = NEARER
        r.target.use()

    def _project_shadows(self, index: int, plane: np.ndarray, light: Light,
                         view_proj: np.ndarray) -> None:
        r = self.renderer
        # in the geometry's frame (`projection`), as the soup's positions are
        origin = r.geometry.origin
        light4 = in_frame(light.homogeneous, origin)
        plane = planes_in_frame(plane[None], origin)[0]
        try:
            m = projection_matrix(-plane[:3] * plane[3], plane[:3], light4)
        except ValueError:
            return  # the light lies in the plane (or grazes it): it casts no shadow onto it
        passes.set_uniform(self.program, "u_view_proj_planar", gl_matrix(view_proj @ m))
        passes.set_uniform(self.program, "u_plane", tuple(float(x) for x in plane))
        passes.set_uniform(self.program, "u_light", tuple(float(x) for x in light4))
        r.target.use(colour=False, depth=False)
        r.ctx.enable_only(moderngl.DEPTH_TEST)  # no culling: every caster triangle projects
        r.ctx.depth_func = NEARER_OR_EQUAL
        r.ctx.polygon_offset = POLYGON_OFFSET
        try:
            with planar_shadow_once(r.gl):
                for rng in r.geometry.ranges:
                    if rng.index != index:
                        self.vao.render(moderngl.TRIANGLES, vertices=3 * rng.count,
                                        first=3 * rng.first)
        finally:
            r.ctx.polygon_offset = (0.0, 0.0)
            r.ctx.depth_func = NEARER
            r.target.use()

    def release(self) -> None:
        if self.vao is not None:
            make_current(self.renderer.ctx)
            self.vao.release()
            self.program.release()
            self.vao = None

    def __enter__(self) -> "PlanarShadows":
        return self

    def __exit__(self, *exc) -> None:
        self.release()


def render_planar(scene: Scene, receiver: str | int | None = None, *, stencil: bool = False,
                  ctx: moderngl.Context | None = None) -> PlanarResult:
    """One frame of `scene` with planar projected shadows (a fresh context unless `ctx`)."""
    with Renderer(scene, ctx) as renderer, PlanarShadows(renderer) as planar:
        return planar.render(receiver, stencil=stencil)
