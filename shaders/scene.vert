#version 450 core
// Scene triangles, as one soup (three vertices per triangle, flat per-triangle attributes).
// The depth pass, the lighting pass and the z-fail near caps all run THIS vertex shader on the
// SAME vertex data, and gl_Position is invariant, so the three passes produce bit-identical
// depths: the lighting pass's depth test EQUAL holds, and a near cap ties exactly with the
// surface it lies on (see shadowvol/volumes.py for why the tie must count as "behind").

uniform mat4 u_view_proj;   // world -> clip, infinite far plane
#ifndef MASK_PASS           // (the mask pass's shade.frag has the page's lights as u_light[])
uniform vec4 u_light;       // (position, 1) for a point or spot light, (-direction, 0) for a
                            // directional light: the homogeneous point the light sits at
#endif

in vec3 in_position;        // world space (float32: what the GPU draws)
in vec3 in_normal;          // unit face normal, cross(v1 - v0, v2 - v0) as wound
in vec3 in_corner;          // the triangle's first corner v0 (the same for its three vertices)
in int in_object;           // index of the object (row of the material texture)

out vec3 v_world;
flat out vec3 v_normal;
flat out float v_facing;    // normal . (L - v0): > 0 when the light is on the normal's side
flat out int v_object;
flat out int v_triangle;    // the triangle's index in the soup: three vertices each, drawn
                            // from vertex 0 (`first` counts in gl_VertexID)

invariant gl_Position;

void main() {
    gl_Position = u_view_proj * vec4(in_position, 1.0);
    v_world = in_position;
    v_normal = in_normal;
    // Per triangle, not per pixel: the sign of n . l is constant over a flat triangle, and the
    // three vertices compute the same value from the same flat inputs.
#ifndef MASK_PASS
    v_facing = dot(in_normal, u_light.xyz - u_light.w * in_corner);
#endif
    v_object = in_object;
    v_triangle = gl_VertexID / 3;
}
