#version 450 core
// Far caps for z-fail: the scene triangle projected from the light to infinity,
// V -> (V - L, 0) for a point light.  (A directional light's far cap is a single point at
// infinity and is never drawn.)

uniform mat4 u_view_proj;
uniform vec4 u_light;  // (position, 1)

in vec3 in_position;

invariant gl_Position;

void main() {
    gl_Position = u_view_proj * vec4(in_position * u_light.w - u_light.xyz, 0.0);
}
