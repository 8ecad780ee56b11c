#version 450 core
// The shadow map's depth: LINEAR in the distance from the light, as cube shadow maps store it
// (a point or spot light: |p - L|; a directional light: the distance along its travel), mapped
// from [near, far] to [0, 1].  So the map's resolution in depth is the same near and far, and
// what the measurements show is its texels and its bias, not a projection's depth curve.  The
// world position is interpolated perspective-correctly, so the distance is exact per fragment.

uniform vec4 u_light;          // (L, 1) for a point or spot light, (travel direction, 0)
uniform vec2 u_depth_range;    // (near, far)

in vec3 v_world;

void main() {
    float along = u_light.w != 0.0 ? length(v_world - u_light.xyz) : dot(v_world, u_light.xyz);
    gl_FragDepth = clamp((along - u_depth_range.x) / (u_depth_range.y - u_depth_range.x),
                         0.0, 1.0);
}
