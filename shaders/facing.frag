#version 450 core
// The ground truth's per-light pass (shadowvol.raster.truth), over the whole screen after every
// light's volume count: per pixel and light, whether the visible side faces the light (n . l > 0
// and inside a spot's cone) and whether it is lit (facing and the light's unshadowed bit set).
// Both come from one evaluation of shade.frag's tests (keep the expressions identical), so
// lit is facing & unshadowed bit for bit and cast = facing & ~lit is exactly "facing, yet some
// volume counts here".

#ifndef LIGHTS
#define LIGHTS 1        // lights in this page, at most 23 (bits exact in a float32)
#endif

uniform sampler2D u_position;   // world position (xyz); w: +-(triangle + 1), 0: uncovered
uniform usampler2D u_unshadowed; // bit i: light i's stencil count is 0 here
uniform vec4 u_light[LIGHTS];           // (position, 1) or (-direction, 0)
uniform vec3 u_spot_direction[LIGHTS];  // unit; used when u_spot_cos > -2
uniform float u_spot_cos[LIGHTS];       // cos of the cone's half-angle; -2 for no cone
layout(std430, binding = 0) readonly buffer Triangles {
    vec4 triangle_data[];       // per triangle: (unit normal, object), (first corner, 0)
};

layout(location = 0) out vec2 f_bits;  // x: bit i lit by light i; y: bit i faces light i

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 position = texelFetch(u_position, p, 0);
    // never 0 (uncovered): the pass is depth-tested to the covered pixels (truth.TruthPass.run),
    // and the others keep the clear value 0
    int surface = int(position.w);
    bool front = surface > 0;
    int t = abs(surface) - 1;
    vec3 normal = triangle_data[2 * t].xyz;
    vec3 corner = triangle_data[2 * t + 1].xyz;
    vec3 world = position.xyz;
    uint unshadowed = texelFetch(u_unshadowed, p, 0).r;
    uint lit = 0u;
    uint faces = 0u;
    for (int i = 0; i < LIGHTS; ++i) {
        // the visible side faces the light (n . l > 0) and lies inside a spot's cone; every
        // pixel evaluates it all and selects (shade.frag says why)
        precise float facing = dot(normal, u_light[i].xyz - u_light[i].w * corner);
        float side = front ? facing : -facing;
        vec3 to_light = u_light[i].xyz - u_light[i].w * world;
        vec3 l = normalize(to_light);
        bool faced = side > 0.0 &&
                     !(u_spot_cos[i] > -2.0 && dot(-l, u_spot_direction[i]) < u_spot_cos[i]);
        faces |= faced ? 1u << uint(i) : 0u;
        lit |= faced && (unshadowed & (1u << uint(i))) != 0u ? 1u << uint(i) : 0u;
    }
    f_bits = vec2(float(lit), float(faces));
}
