#version 450 core
// Depth + ambient pass: ka * scene ambient, linear RGB; alpha 1 marks covered pixels.

uniform sampler2D u_materials;  // row = object: texel 0 ka, 1 kd, 2 (ks, shininess)
uniform vec3 u_ambient;

flat in int v_object;

layout(location = 0) out vec4 f_colour;
layout(location = 1) out float f_lit;

void main() {
    vec3 ka = texelFetch(u_materials, ivec2(0, v_object), 0).rgb;
    f_colour = vec4(ka * u_ambient, 1.0);
    f_lit = 0.0;
}
