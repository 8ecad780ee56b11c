"""Shadow mapping (Williams 1978), drawn in GL to be measured against the exact shadow.

The map is fitted to what the camera sees (the `points` given, the visible surface points):
a point or spot light looks from its position at them with a perspective frustum just wide
enough; a directional light with an orthographic box around them, reaching back along its
travel to the farthest caster.  Every triangle of the scene is drawn into an N x N depth
texture (24-bit) that stores a depth linear in the distance from the light (shadowmap.frag).
A point is then shadowed when its own depth, less the bias, lies behind the map's texel
(`shadowed`: numpy, float64, with percentage-closer filtering over K x K texels).  Points
outside the map count as lit, as the usual clamp-to-border shadow maps have them.

The artefacts are the usual ones (LearnOpenGL's "Shadow Mapping"): acne where a lit surface
is found behind its own texel's depth (too little bias, a surface grazed by the light),
peter-panning where a shadow detaches from its caster or thin casters vanish (too much bias),
and blocky edges (too few texels).
"""

from __future__ import annotations

from dataclasses import dataclass

import moderngl
import numpy as np

from shadowvol.raster import glsl
from shadowvol.raster.platform.context import make_current
from shadowvol.scene import DirectionalLight, PointLight, Scene, SpotLight

# A point or spot light's frustum may open up to this half-angle (degrees) around the visible
# points: beyond it one map cannot hold them (a cube map would) and the command says so.
MAX_HALF_ANGLE = 80.0
# The frustum and the box are widened by this share, so that no visible point sits on the
# map's very border.
MARGIN = 0.02


@dataclass(frozen=True)
class LightView:
    """Where the map looks from.  Coordinates are world minus `origin` (float64 here, float32
    on the GPU: the light's position, or the visible points' centre, keeps them small).

    view_projection : (4, 4) float64, to clip space
    origin          : (3,) float64
    light           : (4,) float64, (0, 0, 0, 1) for a point or spot light (at the origin),
                      (t, 0) for a directional light travelling along unit t
    depth_range     : (near, far): the distances from the light that depth 0 and 1 stand for
    """

    view_projection: np.ndarray
    origin: np.ndarray
    light: np.ndarray
    depth_range: tuple[float, float]

    def depth(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) world points -> (n,) float64 linear depth in the map's units (0..1 in range)."""
        p = np.asarray(points, float) - self.origin
        along = np.linalg.norm(p, axis=1) if self.light[3] else p @ self.light[:3]
        near, far = self.depth_range
        return (along - near) / (far - near)

    def texel_coordinates(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) world points -> (n, 2) float64 map coordinates (u, v) in 0..1 inside."""
        p = np.asarray(points, float) - self.origin
        clip = np.concatenate([p, np.ones((len(p), 1))], axis=1) @ self.view_projection.T
        return (clip[:, :2] / clip[:, 3:4] + 1.0) / 2.0


def _basis(forward: np.ndarray) -> np.ndarray:
    """(3, 3) rows right, up, back of a view looking along unit `forward`."""
    helper = np.array([0.0, 1.0, 0.0]) if abs(forward[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    right = np.cross(forward, helper)
    right /= np.linalg.norm(right)
    return np.stack([right, np.cross(right, forward), -forward])


def fit(scene: Scene, light, points: np.ndarray) -> LightView:
    """The light's view around `points` (n, 3) (the visible surface points), for `light`, a
    point, spot or directional light of `scene`.  ValueError when one map cannot hold them."""
    points = np.asarray(points, float)
    vertices = np.concatenate([o.vertices for o in scene.objects])
    if isinstance(light, DirectionalLight):
        t = light.direction / np.linalg.norm(light.direction)
        origin = points.mean(axis=0)
        rot = _basis(t)
        local = (points - origin) @ rot.T
        half = np.abs(local[:, :2]).max(axis=0) * (1 + MARGIN) + 1e-9
        near = float(((vertices - origin) @ t).min()) - 1e-6
        far = float(((points - origin) @ t).max()) * (1 + MARGIN) + 1e-6
        view = np.eye(4)
        view[:3, :3] = rot
        proj = np.diag([1 / half[0], 1 / half[1], -2 / (far - near), 1.0])
        proj[2, 3] = -(far + near) / (far - near)
        # the view's z is -(distance along t); the box spans along-distances near .. far
        return LightView(proj @ view, origin, np.append(t, 0.0), (near, far))
    if not isinstance(light, (PointLight, SpotLight)):
        raise ValueError(f"shadow maps here take point, spot and directional lights, not "
                         f"{type(light).__name__}")
    origin = np.asarray(light.position, float)
    rel = points - origin
    dist = np.linalg.norm(rel, axis=1)
    if (dist <= 0).any():
        raise ValueError("a visible point lies on the light")
    unit = rel / dist[:, None]
    forward = unit.mean(axis=0)
    forward /= np.linalg.norm(forward)
    rot = _basis(forward)
    local = rel @ rot.T                      # x right, y up, -z forward
    ahead = -local[:, 2]
    if ahead.min() <= np.cos(np.radians(MAX_HALF_ANGLE)) * dist[np.argmin(ahead)]:
        raise ValueError(f"the visible points spread over more than {2 * MAX_HALF_ANGLE:g} "
                         f"degrees around this light: one shadow map cannot hold them (a "
                         f"cube map would)")
    tan = np.abs(local[:, :2] / ahead[:, None]).max(axis=0) * (1 + MARGIN) + 1e-9
    far = float(dist.max()) * (1 + MARGIN)
    near = far * 1e-5                        # clipping only: the depth stored is linear
    view = np.eye(4)
    view[:3, :3] = rot
    proj = np.zeros((4, 4))
    proj[0, 0], proj[1, 1] = 1 / tan[0], 1 / tan[1]
    proj[2, 2], proj[2, 3] = -(far + near) / (far - near), -2 * far * near / (far - near)
    proj[3, 2] = -1.0
    return LightView(proj @ view, origin, np.array([0.0, 0.0, 0.0, 1.0]), (0.0, far))


def depth_map(ctx: moderngl.Context, scene: Scene, view: LightView, resolution: int
              ) -> np.ndarray:
    """(N, N) float32: the linear depth (0..1, 1 where nothing) of the nearest triangle seen
    from the light per texel; row 0 is the map's v = 0 edge."""
    make_current(ctx)
    tris = np.concatenate([o.vertices[o.faces].reshape(-1, 3) for o in scene.objects])
    data = (tris - view.origin).astype(np.float32)
    program = glsl.program(ctx, "shadowmap.vert", "shadowmap.frag")
    owned = [program]
    previous = ctx.fbo   # bound again before ours goes: moderngl rebinds its last-used one
    try:
        glsl.set_uniform(program, "u_light_view_projection",
                         tuple(view.view_projection.astype(np.float32).T.reshape(-1)))
        glsl.set_uniform(program, "u_light", tuple(view.light.astype(np.float32)))
        glsl.set_uniform(program, "u_depth_range", tuple(np.float32(view.depth_range)))
        vbo = ctx.buffer(data.tobytes())
        owned.append(vbo)
        vao = ctx.vertex_array(program, [(vbo, "3f", "a_position")])
        owned.append(vao)
        depth = ctx.depth_texture((resolution, resolution))
        owned.append(depth)
        fbo = ctx.framebuffer(depth_attachment=depth)
        owned.append(fbo)
        fbo.use()
        ctx.viewport = (0, 0, resolution, resolution)
        ctx.enable_only(moderngl.DEPTH_TEST)
        ctx.depth_func = "<"
        fbo.clear(depth=1.0)
        vao.render(moderngl.TRIANGLES)
        raw = np.frombuffer(depth.read(alignment=1), np.float32)
        return raw.reshape(resolution, resolution).copy()
    finally:
        previous.use()
        for thing in reversed(owned):
            thing.release()


def shadowed(view: LightView, depth: np.ndarray, points: np.ndarray, bias: float,
             pcf: int = 1) -> np.ndarray:
    """(n,) float64: the share of the K x K texels around each point's (K = `pcf`) whose depth
    lies in front of the point's own depth less `bias` (map units, as LearnOpenGL's bias);
    0 outside the map.  A point counts as shadowed where the share exceeds 1/2."""
    n = depth.shape[0]
    uv = view.texel_coordinates(points)
    own = view.depth(points) - bias
    inside = np.all((uv >= 0) & (uv < 1), axis=1)
    centre = np.floor(np.clip(uv, 0, 1 - 1e-12) * n).astype(np.int64)
    offsets = np.arange(pcf) - (pcf - 1) // 2
    share = np.zeros(len(points))
    for dy in offsets:
        for dx in offsets:
            i = np.clip(centre[:, 0] + dx, 0, n - 1)
            j = np.clip(centre[:, 1] + dy, 0, n - 1)
            share += depth[j, i] < own
    return np.where(inside, share / pcf ** 2, 0.0)
