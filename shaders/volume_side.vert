#version 450 core
// Side quads of shadow volumes built on the CPU: homogeneous world positions, w = 1 on the
// silhouette edge and w = 0 for its copy extruded to infinity, away from the light.

uniform mat4 u_view_proj;

in vec4 in_position;

invariant gl_Position;

void main() {
    gl_Position = u_view_proj * in_position;
}
