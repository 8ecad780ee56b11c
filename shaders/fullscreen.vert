#version 450 core
// One triangle covering the whole viewport (vertices 0, 1, 2 without attributes), for the
// per-pixel passes of the deferred frame, at window depth 0: the depth buffer's clear value
// (reversed depth, nothing drawn), so a depth test "<" keeps exactly the covered pixels.

void main() {
    vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    gl_Position = vec4(p, 0.0, 1.0);
}
