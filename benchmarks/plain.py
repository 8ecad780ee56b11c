"""The physical floor every frame ratio is quoted against: a plain moderngl frame of the same
triangles and camera, written here and nowhere else (no shadowvol code on its GL path).

One indexed draw of every triangle (smooth vertex normals, back-face culling, depth test),
Blinn-Phong for one point light in the fragment shader, into an RGBA8 + depth framebuffer, and
an RGBA8 read-back.  No shadows.  This is what any renderer of these triangles must at least
pay on this machine.
"""

from __future__ import annotations

import moderngl
import numpy as np

from shadowvol.raster.projection import view_matrix

VERTEX = """
#version 330
uniform mat4 u_mvp;
in vec3 in_position;
in vec3 in_normal;
out vec3 v_position;
out vec3 v_normal;
void main() {
    gl_Position = u_mvp * vec4(in_position, 1.0);
    v_position = in_position;
    v_normal = in_normal;
}
"""
# one point light's Blinn-Phong from v_position and v_normal (the plain frame's, and the
# lighting floor's on per-pixel values)
BLINN_PHONG = """
    vec3 n = normalize(v_normal);
    vec3 l = normalize(u_light - v_position);
    vec3 h = normalize(l + normalize(u_eye - v_position));
    float d = max(dot(n, l), 0.0);
    float s = pow(max(dot(n, h), 0.0), 32.0);
    f_colour = vec4(vec3(0.05) + vec3(0.7) * d + vec3(0.3) * s, 1.0);
"""
FRAGMENT = """
#version 330
uniform vec3 u_light;
uniform vec3 u_eye;
in vec3 v_position;
in vec3 v_normal;
out vec4 f_colour;
void main() {""" + BLINN_PHONG + """}
"""


def perspective(camera, aspect: float, far_factor: float = 1e4) -> np.ndarray:
    """(4, 4) the classic OpenGL perspective (depth -1..1, near plane camera.near, far plane
    far_factor * near), for the plain frame's ordinary depth test."""
    f = 1.0 / np.tan(np.radians(camera.fov_y) / 2)
    n = camera.near
    far = n * far_factor
    return np.array([[f / aspect, 0, 0, 0], [0, f, 0, 0],
                     [0, 0, (far + n) / (n - far), 2 * far * n / (n - far)], [0, 0, -1, 0]])


class PlainFrame:
    """`PlainFrame(ctx, scene)()` renders one frame and returns (H, W, 4) uint8 (bottom row
    first, as GL reads it).  Call `release()`."""

    def __init__(self, ctx: moderngl.Context, scene):
        self.ctx = ctx
        verts, normals, faces, offset = [], [], [], 0
        for o in scene.objects:
            v = np.asarray(o.vertices, np.float64)
            f = np.asarray(o.faces, np.int64)
            tri = v[f]
            fn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
            vn = np.zeros_like(v)
            for k in range(3):
                np.add.at(vn, f[:, k], fn)
            vn /= np.maximum(np.linalg.norm(vn, axis=1, keepdims=True), 1e-30)
            verts.append(v)
            normals.append(vn)
            faces.append(f + offset)
            offset += len(v)
        self.program = ctx.program(vertex_shader=VERTEX, fragment_shader=FRAGMENT)
        self.vbo = ctx.buffer(np.concatenate(verts).astype("f4").tobytes())
        self.nbo = ctx.buffer(np.concatenate(normals).astype("f4").tobytes())
        self.ibo = ctx.buffer(np.concatenate(faces).astype("i4").tobytes())
        self.vao = ctx.vertex_array(self.program, [(self.vbo, "3f", "in_position"),
                                                   (self.nbo, "3f", "in_normal")],
                                    index_buffer=self.ibo, index_element_size=4)
        self.colour = ctx.renderbuffer((scene.width, scene.height), 4)
        self.depth = ctx.depth_renderbuffer((scene.width, scene.height))
        self.fbo = ctx.framebuffer(self.colour, self.depth)
        self.out = np.empty((scene.height, scene.width, 4), np.uint8)
        light = scene.lights[0]
        position = getattr(light, "position", None)
        if position is None:  # a directional light: a point far along its reverse direction
            position = -np.asarray(light.direction) * 1e4
        self.program["u_mvp"].write(np.ascontiguousarray(
            (perspective(scene.camera, scene.aspect) @ view_matrix(scene.camera)).T,
            np.float32).tobytes())
        self.program["u_light"].value = tuple(float(x) for x in position)
        self.program["u_eye"].value = tuple(float(x) for x in scene.camera.eye)

    def __call__(self) -> np.ndarray:
        self.fbo.use()
        self.ctx.enable_only(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        self.ctx.depth_func = "<"
        self.ctx.cull_face = "back"
        self.ctx.front_face = "ccw"
        self.fbo.clear(0.1, 0.1, 0.1, 1.0, depth=1.0)
        self.vao.render(moderngl.TRIANGLES)
        self.fbo.read_into(self.out, components=4)
        return self.out

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    def release(self) -> None:
        for obj in (self.vao, self.fbo, self.colour, self.depth, self.ibo, self.nbo, self.vbo,
                    self.program):
            obj.release()


DEPTH_VERTEX = """
#version 330
uniform mat4 u_mvp;
in vec3 in_position;
void main() {
    gl_Position = u_mvp * vec4(in_position, 1.0);
}
"""


class DepthFloor:
    """`DepthFloor(ctx, plain_frame)()`: the least GL work of ANY exact shadowed frame of the
    scene: one indexed draw of every triangle into depth only, with NO back-face culling (an
    exact frame cannot cull: in float32 a back face can win the depth test at a silhouette,
    `shadowvol.raster.methods.cullable`), an empty fragment shader, no colour, no read-back,
    then glFinish.  The plain frame's buffers and camera (`PlainFrame`), so it draws the same
    triangles.  A shadow-volume frame pays at least this plus its volume passes."""

    def __init__(self, ctx: moderngl.Context, plain: PlainFrame):
        self.ctx = ctx
        self.program = ctx.program(vertex_shader=DEPTH_VERTEX,
                                   fragment_shader="#version 330\nvoid main() {}\n")
        self.program["u_mvp"].write(plain.program["u_mvp"].read())
        self.vao = ctx.vertex_array(self.program, [(plain.vbo, "3f", "in_position")],
                                    index_buffer=plain.ibo, index_element_size=4)
        self.fbo = ctx.framebuffer(depth_attachment=plain.depth)

    def __call__(self) -> None:
        self.fbo.use()
        self.ctx.enable_only(moderngl.DEPTH_TEST)
        self.ctx.depth_func = "<"
        self.fbo.clear(depth=1.0)
        self.vao.render(moderngl.TRIANGLES)
        self.ctx.finish()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    def release(self) -> None:
        for obj in (self.vao, self.fbo, self.program):
            obj.release()


IMAGE_FRAGMENT = """
#version 330
layout(location = 0) out vec4 f_colour;
layout(location = 1) out float f_bits;
void main() {
    f_colour = vec4(0.5, 0.5, 0.5, 1.0);
    f_bits = 3.0 / 255.0;
}
"""


MASK_FRAGMENT = """
#version 330
layout(location = 0) out float f_bits;
void main() {
    f_bits = 3.0 / 255.0;
}
"""


class ImageFloor:
    """`ImageFloor(ctx, plain_frame)()`: the least GL work and read-back of any exact frame that
    returns the image, the lit masks and the coverage (the renderer's default outputs), its
    volume passes aside: `DepthFloor`'s draw (every triangle, no culling) writing besides depth
    a float colour and one byte of bits a pixel, both cleared first (every returned pixel is
    written, covered or not), then both read back as the caller gets them: the colour as RGB
    float32, the bits as bytes; no flip, no conversion.  The colour target is RGBA32F: the
    image is exact float32 RGB, and GL 4.5 requires no 3-channel 32-bit float format to be
    renderable; the bits are R8 (coverage and up to 7 lights' lit bits in one byte).  The
    colour is a constant: no shading arithmetic is counted, only what storing and returning
    the image and the masks cost.  `colour=False`: the bits alone (`MaskFloor`)."""

    def __init__(self, ctx: moderngl.Context, plain: PlainFrame, colour: bool = True):
        self.ctx = ctx
        self.program = ctx.program(vertex_shader=DEPTH_VERTEX,
                                   fragment_shader=IMAGE_FRAGMENT if colour else MASK_FRAGMENT)
        self.program["u_mvp"].write(plain.program["u_mvp"].read())
        self.vao = ctx.vertex_array(self.program, [(plain.vbo, "3f", "in_position")],
                                    index_buffer=plain.ibo, index_element_size=4)
        w, h = plain.colour.size
        self.colour = ctx.texture((w, h), 4, dtype="f4") if colour else None
        self.bits = ctx.texture((w, h), 1, dtype="f1")
        self.fbo = ctx.framebuffer([t for t in (self.colour, self.bits) if t is not None],
                                   plain.depth)
        self.image = np.empty((h, w, 3), np.float32) if colour else None
        self.lit = np.empty((h, w), np.uint8)
        self._clear = (0.1, 0.1, 0.1, 0.0) if colour else (0.0, 0.0, 0.0, 0.0)

    def __call__(self) -> None:
        self.fbo.use()
        self.ctx.enable_only(moderngl.DEPTH_TEST)
        self.ctx.depth_func = "<"
        self.fbo.clear(*self._clear, depth=1.0)
        self.vao.render(moderngl.TRIANGLES)
        if self.image is not None:
            self.fbo.read_into(self.image, components=3, attachment=0, dtype="f4")
        self.fbo.read_into(self.lit, components=1, attachment=0 if self.colour is None else 1,
                           dtype="f1")

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    def release(self) -> None:
        for obj in (self.vao, self.fbo, self.colour, self.bits, self.program):
            if obj is not None:
                obj.release()


class MaskFloor(ImageFloor):
    """`MaskFloor(ctx, plain_frame)()`: the least GL work and read-back of any exact frame that
    returns the masks alone (lit and coverage, `outputs=("lit", "coverage")`), its volume
    passes aside: `ImageFloor`'s draw and bits without its colour, the bits cleared to 0.  Why
    the byte must be written in the draw: whether a pixel can be lit depends on the side of its
    visible triangle the light is on, known only to the fragment that wins the depth test; a
    second draw of the triangles that face the light, or one draw split by facing, would
    change the depth ties the exact frame must keep."""

    def __init__(self, ctx: moderngl.Context, plain: PlainFrame):
        super().__init__(ctx, plain, colour=False)


FULLSCREEN_VERTEX = """
#version 330
void main() {
    vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    gl_Position = vec4(p, 1.0, 1.0);
}
"""
# BLINN_PHONG, with the position and the normal made per pixel from gl_FragCoord
# (no load, nothing the compiler can fold), and the same fragment with a constant colour
LIGHTING_FRAGMENT = """
#version 330
uniform vec3 u_light;
uniform vec3 u_eye;
out vec4 f_colour;
void main() {
    vec2 q = gl_FragCoord.xy * 0.001;
    vec3 v_position = vec3(q.x, 0.0, q.y);
    vec3 v_normal = vec3(q.y, 1.0, q.x);""" + BLINN_PHONG + """}
"""
FLAT_FRAGMENT = """
#version 330
out vec4 f_colour;
void main() {
    vec2 q = gl_FragCoord.xy * 0.001;
    f_colour = vec4(q, 0.5, 1.0);
}
"""


class LightingFloor:
    """The per-pixel lighting arithmetic of one light, once per covered pixel: `lit()` and
    `flat()` are one full-screen pass each over the covered pixels of the scene (depth-tested
    against a depth buffer of its own, drawn once here as `DepthFloor` draws it), into a colour
    buffer, then glFinish.  `lit`'s pass evaluates the plain frame's own Blinn-Phong
    (FRAGMENT's expressions on per-pixel values, no loads), `flat`'s writes a per-pixel colour
    without it; everything else is the same, so median(lit) − median(flat) is what the
    lighting arithmetic alone costs.  Any exact frame that returns the image evaluates at
    least one light's lighting at every covered pixel (forward or deferred), so this adds to
    its image floor."""

    def __init__(self, ctx: moderngl.Context, plain: PlainFrame):
        self.ctx = ctx
        size = plain.colour.size
        self.colour = ctx.renderbuffer(size, 4)
        self.depth_buffer = ctx.depth_renderbuffer(size)
        self.fbo = ctx.framebuffer(self.colour, self.depth_buffer)
        depth = ctx.program(vertex_shader=DEPTH_VERTEX,
                            fragment_shader="#version 330\nvoid main() {}\n")
        depth["u_mvp"].write(plain.program["u_mvp"].read())
        vao = ctx.vertex_array(depth, [(plain.vbo, "3f", "in_position")],
                               index_buffer=plain.ibo, index_element_size=4)
        self.fbo.use()
        ctx.enable_only(moderngl.DEPTH_TEST)
        ctx.depth_func = "<"
        self.fbo.clear(0.1, 0.1, 0.1, 1.0, depth=1.0)
        vao.render(moderngl.TRIANGLES)
        vao.release()
        depth.release()
        self.lighting = ctx.program(vertex_shader=FULLSCREEN_VERTEX,
                                    fragment_shader=LIGHTING_FRAGMENT)
        for name in ("u_light", "u_eye"):
            self.lighting[name].value = plain.program[name].value
        self.flat_program = ctx.program(vertex_shader=FULLSCREEN_VERTEX,
                                        fragment_shader=FLAT_FRAGMENT)
        self.lit_vao = ctx.vertex_array(self.lighting, [])
        self.flat_vao = ctx.vertex_array(self.flat_program, [])

    def _pass(self, vao: moderngl.VertexArray) -> None:
        self.fbo.depth_mask = False
        self.fbo.use()
        self.ctx.enable_only(moderngl.DEPTH_TEST)
        self.ctx.depth_func = ">"   # the full-screen triangle at the far plane: covered pixels
        vao.render(moderngl.TRIANGLES, vertices=3)
        self.ctx.finish()

    def lit(self) -> None:
        self._pass(self.lit_vao)

    def flat(self) -> None:
        self._pass(self.flat_vao)

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    def release(self) -> None:
        for obj in (self.lit_vao, self.flat_vao, self.lighting, self.flat_program, self.fbo,
                    self.colour, self.depth_buffer):
            obj.release()
