#version 450 core
// The geometry pass of the deferred frame (scene.vert, one indexed draw of every triangle):
// depth, the ambient term ka * ambient with alpha 1 (covered), the coverage bit, and what the
// lighting pass needs per pixel.  The interpolated world position is stored as the forward
// lighting pass would have interpolated it (same triangle, same vertices), and the surface is
// the triangle's index in the draw (gl_PrimitiveID), plus one, negated when its back face is
// seen: the lighting pass fetches the triangle's flat data (normal, first corner, object) by it.

uniform sampler2D u_materials;  // row = object: texel 0 ka, 1 kd, 2 (ks, shininess)
uniform vec3 u_ambient;

in vec3 v_world;
flat in int v_object;

layout(location = 0) out vec4 f_colour;
layout(location = 1) out float f_bits;     // bit 0: covered (the lighting pass adds 2^(i+1))
layout(location = 2) out vec4 f_position;
layout(location = 3) out int f_surface;    // 0: nothing drawn (the clear value)

void main() {
    vec3 ka = texelFetch(u_materials, ivec2(0, v_object), 0).rgb;
    f_colour = vec4(ka * u_ambient, 1.0);
    f_bits = 1.0;
    f_position = vec4(v_world, 1.0);
    f_surface = gl_FrontFacing ? gl_PrimitiveID + 1 : -(gl_PrimitiveID + 1);
}
