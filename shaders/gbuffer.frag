#version 450 core
// The geometry pass of the deferred frame (scene.vert over the soup, every triangle): depth,
// and what the shading pass needs per pixel: the world position, the varying the forward
// lighting pass would have interpolated (same triangle, same vertices), and in w the surface:
// the triangle's index in the scene plus one, negated where its back face is seen, as a float
// (exact below 2^24), 0 where nothing is drawn (the clear value).  shade.frag fetches the
// triangle's flat data (normal, first corner, object) by it.
// SURFACE (a scene with textures or vertex colours): also the interpolated UVs and vertex
// colour (perspective-correct, GL's default), from which shade.frag makes the base colour.

in vec3 v_world;
flat in int v_triangle;

layout(location = 0) out vec4 f_position;
#ifdef SURFACE
in vec2 v_uv;
in vec3 v_colour;
layout(location = 1) out vec2 f_uv;
layout(location = 2) out vec4 f_tint;
#endif

void main() {
    float surface = float(v_triangle + 1);
    f_position = vec4(v_world, gl_FrontFacing ? surface : -surface);
#ifdef SURFACE
    f_uv = v_uv;
    f_tint = vec4(v_colour, 1.0);
#endif
}
