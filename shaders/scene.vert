#version 450 core
// Scene triangles, as one soup (three vertices per triangle, flat per-triangle attributes).
// The depth pass, the lighting pass and the z-fail near caps all run THIS vertex shader on the
// SAME vertex data, and gl_Position is invariant, so the three passes produce bit-identical
// depths: the lighting pass's depth test EQUAL holds, and a near cap ties exactly with the
// surface it lies on (see shadowvol/raster/volumes.py for why the tie must count as "behind").

uniform mat4 u_view_proj;   // world -> clip, infinite far plane
#ifndef MASK_PASS
uniform vec4 u_light;       // (position, 1) for a point or spot light, (-direction, 0) for a
                            // directional light: the homogeneous point the light sits at
#elif LIGHTS > 0            // the mask pass: the page's lights, as shade.frag has them
uniform vec4 u_light[LIGHTS];
#endif

in vec3 in_position;        // world space (float32: what the GPU draws)
in vec3 in_normal;          // unit face normal, cross(v1 - v0, v2 - v0) as wound
in vec3 in_corner;          // the triangle's first corner v0 (the same for its three vertices)
in int in_object;           // index of the object (row of the material texture)
#ifdef SURFACE              // the geometry pass of a scene with textures or vertex colours
in vec2 in_uv;              // the vertex's texture coordinates (glTF's convention)
in vec3 in_colour;          // its linear vertex colour (1 where the object has none)
out vec2 v_uv;
out vec3 v_colour;
#endif

out vec3 v_world;
flat out vec3 v_normal;
flat out float v_facing;    // normal . (L - v0): > 0 when the light is on the normal's side
flat out int v_object;
flat out int v_triangle;    // the triangle's index in the soup: three vertices each, drawn
                            // from vertex 0 (`first` counts in gl_VertexID)
#ifdef MASK_PASS
flat out uint v_front_lights; // bit i + 1: light i is on the front side of the triangle
flat out uint v_back_lights;  // (n . l > 0), on the back side (n . l < 0): shade.frag's test
#endif

invariant gl_Position;

void main() {
    gl_Position = u_view_proj * vec4(in_position, 1.0);
    v_world = in_position;
    v_normal = in_normal;
    // Per triangle, not per pixel: the sign of n . l is constant over a flat triangle, and the
    // three vertices compute the same value from the same flat inputs.  `precise`, here and in
    // shade.frag and facing.frag: no compiler may fuse or reorder it differently in one stage
    // than in another, so every pass gets the same float32 value (llvmpipe fuses nothing, a
    // GPU compiler may)
#ifndef MASK_PASS
    precise float facing = dot(in_normal, u_light.xyz - u_light.w * in_corner);
    v_facing = facing;
#else
    // shade.frag's `facing` for each light of the page, the same expression on the same
    // float32 values (its triangle record holds this normal and corner): the visible side
    // faces light i where it is the front and facing > 0, or the back and -facing > 0
    v_front_lights = 0u;
    v_back_lights = 0u;
#if LIGHTS > 0
    for (int i = 0; i < LIGHTS; ++i) {
        precise float facing = dot(in_normal, u_light[i].xyz - u_light[i].w * in_corner);
        v_front_lights |= facing > 0.0 ? 2u << uint(i) : 0u;
        v_back_lights |= -facing > 0.0 ? 2u << uint(i) : 0u;
    }
#endif
#endif
    v_object = in_object;
    v_triangle = gl_VertexID / 3;
#ifdef SURFACE
    v_uv = in_uv;
    v_colour = in_colour;
#endif
}
