#version 450 core
// The shadow map's depth pass: every triangle seen from the light (shadowmap.py).  The world
// position goes on to the fragment shader, which stores a depth LINEAR in the distance from
// the light.

uniform mat4 u_light_view_projection;

layout(location = 0) in vec3 a_position;

out vec3 v_world;

void main() {
    v_world = a_position;
    gl_Position = u_light_view_projection * vec4(a_position, 1.0);
}
