#version 450 core
// One triangle covering the whole viewport (vertices 0, 1, 2 without attributes), for the
// per-pixel passes of the deferred frame.  Its depth is never tested.

void main() {
    vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    gl_Position = vec4(p, 0.0, 1.0);
}
