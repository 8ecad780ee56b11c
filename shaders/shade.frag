#version 450 core
#if defined(MASK_PASS) && defined(STENCIL_BITS)
#extension GL_ARB_shader_stencil_export : require
#endif
// The deferred frame's one shading pass, over the whole screen after every light's volume
// count (drawn twice, split by the last light's stencil test): per pixel the ambient term ka * ambient plus, for each light whose unshadowed bit is
// set, the light's direct Phong term where n . l > 0 and inside a spot's cone, which also sets
// the light's lit bit.  The expressions are phong.frag's and scene.vert's (keep them identical),
// on the same float32 inputs: the interpolated world position from the G-buffer and the
// triangle's flat values from the per-triangle buffer, so the masks and the image are the
// forward passes' bit for bit.  Terms are added in light order, as the forward passes blended
// them.
//
// MASKS_ONLY: the lit bits alone, no colour.  SRGB_OUT: the colour encoded to 8-bit sRGB (a
// frame of one page whose float image is not asked for).
//
// MASK_PASS (with MASKS_ONLY): the geometry pass of a mask-only frame (scene.vert over the
// soup), before any volume count.  The same tests on the same inputs, with every light taken
// as unshadowed: n . l > 0 per triangle in scene.vert (the same expression on the same
// float32 normal and corner as the triangle's record here, both signs), the side from
// gl_FrontFacing instead of the G-buffer's sign, a spot's cone on the interpolated world
// position the geometry pass would have stored.  It writes coverage and "faces the light"
// bits, and after each light's count the mark pass clears that light's bit where the count is
// not 0 (passes.clear_shadowed).  Only the pixels that survive the depth test keep their
// bits, so they are the deferred frame's lit bits exactly.
//
// SURFACE (a scene with textures or vertex colours): the base colour, the G-buffer's
// interpolated vertex colour times the object's texture at the G-buffer's UVs, multiplies
// ka and kd; `base_colour` below is docs/CONVENTIONS.md's rule, "Textures" (raytrace.texture
// is the ray tracer's): texels fetched by index from one storage buffer, each decoded from
// sRGB by the table, then filtered (nearest, or bilinear at level 0), indices wrapped.
//
// STENCIL_BITS (with MASK_PASS, at most 6 lights): the same bits written into the stencil
// instead of a colour target (gl_FragStencilRefARB, stencil.exported_bits), reversed: bit 7
// covered, bit 6 - i light i, and the low bits 0, where the lights' counts then go
// (stencil.mask_layout).

#ifndef LIGHTS
#define LIGHTS 1        // lights in this page, at most 23 (lit bits 1..23 and coverage: exact
#endif                  // in a float32); a constant, so that the loop unrolls
#ifndef SPOT_LIGHTS
#define SPOT_LIGHTS 0   // bit i: light i is a spot (has a cone); constants too, so that the
#endif                  // unrolled loop has no cone test where there is no cone, and no
#ifndef EMITTER_LIGHTS  // emitter cosine but for an area light's samples (the same values as
#define EMITTER_LIGHTS 0 // the uniforms' NO_CONE and 0 give; 3 ms less of a 1k frame here)
#endif
#define HAS(lights, i) ((((lights) >> (i)) & 1) != 0)

uniform sampler2D u_materials;  // row = object: texel 0 ka, 1 kd, 2 (ks, shininess)
#ifdef MASK_PASS
in vec3 v_world;                // scene.vert's: what gbuffer.frag stores
flat in uint v_front_lights;    // scene.vert's: bit i + 1 where n . l > 0 for light i, and
flat in uint v_back_lights;     // where -(n . l) > 0
#else
uniform sampler2D u_position;   // world position (xyz) of the visible surface; w: the surface,
                                // +-(triangle + 1), negative for a back face; 0: uncovered
uniform usampler2D u_unshadowed; // bit i: light i's stencil count is 0 here (i < LIGHTS - 1)
#endif
uniform bool u_last_unshadowed; // the last light's: the stencil still holds its count, and the
                                // pass is drawn twice, where it is 0 (true) and where not
uniform vec3 u_eye;
uniform vec3 u_ambient;
uniform bool u_first_page;      // the first page of lights: ambient and the coverage bit
#if LIGHTS > 0
uniform vec4 u_light[LIGHTS];           // (position, 1) or (-direction, 0)
uniform vec3 u_radiance[LIGHTS];
uniform vec3 u_spot_direction[LIGHTS];  // unit; used when u_spot_cos > -2
uniform float u_spot_cos[LIGHTS];       // cos of the cone's half-angle; -2 for no cone
uniform float u_emitter_cosine[LIGHTS]; // 1: a one-sided area light's sample, weighted by the
                                        // cosine at the light, max(-l . u_spot_direction, 0)
#endif
layout(std430, binding = 0) readonly buffer Triangles {
    vec4 triangle_data[];       // per triangle: (unit normal, object), (first corner, 0)
};
#if defined(SURFACE) && !defined(MASK_PASS) && !defined(MASKS_ONLY)
uniform sampler2D u_uv;         // the visible surface's UVs (the geometry pass's)
uniform sampler2D u_tint;       // and its vertex colour (rgb)
layout(std430, binding = 1) readonly buffer Texels {
    uint texels[];              // every texture's RGBA8 sRGB codes, one texture after another
};
// per texture: first texel, width, height, flags (bits 0-1 wrap_s, 2-3 wrap_t: 0 repeat,
// 1 clamp, 2 mirror; bit 4 bilinear)
layout(std430, binding = 2) readonly buffer Records {
    ivec4 records[];
};
layout(std430, binding = 3) readonly buffer Decode {
    float srgb_linear[256];     // 8-bit sRGB code -> linear (float64 rounded to float32)
};

// Texel index i wrapped into 0..n-1 by `mode`.
int wrap_index(int i, int n, int mode) {
    if (mode == 1) {
        return clamp(i, 0, n - 1);
    }
    int period = mode == 0 ? n : 2 * n;
    int k = i % period;
    k = k < 0 ? k + period : k;
    return k < n ? k : period - 1 - k;
}

// Texel (i, j) (column, row from the top) of texture `r`, wrapped and decoded to linear.
vec3 texel(ivec4 r, int i, int j) {
    int x = wrap_index(i, r.y, r.w & 3);
    int y = wrap_index(j, r.z, (r.w >> 2) & 3);
    uint c = texels[r.x + y * r.y + x];
    return vec3(srgb_linear[c & 0xFFu], srgb_linear[(c >> 8) & 0xFFu],
                srgb_linear[(c >> 16) & 0xFFu]);
}

vec3 base_colour(ivec4 r, vec2 uv) {
    vec2 xy = uv * vec2(r.yz);
    if ((r.w & 16) == 0) {
        ivec2 ij = ivec2(floor(xy));
        return texel(r, ij.x, ij.y);
    }
    xy -= 0.5;                  // texel centres at whole numbers
    vec2 f = floor(xy);
    ivec2 ij = ivec2(f);
    vec2 a = xy - f;
    vec3 top = texel(r, ij.x, ij.y) * (1.0 - a.x) + texel(r, ij.x + 1, ij.y) * a.x;
    vec3 bottom = texel(r, ij.x, ij.y + 1) * (1.0 - a.x) + texel(r, ij.x + 1, ij.y + 1) * a.x;
    return top * (1.0 - a.y) + bottom * a.y;
}
#endif

#if defined(MASK_PASS) && !defined(STENCIL_BITS)
layout(location = 0) out uint f_lit_bits;  // bit 0 covered, bit i + 1 faces light i
#elif !defined(MASK_PASS)
layout(location = 0) out vec4 f_colour;
layout(location = 1) out float f_bits;     // bit 0 covered, bit i + 1 lit by light i
#endif

#if LIGHTS > 0
// Inside light i's cone, `l` the unit vector to the light (always, but for a spot light).
bool in_cone(int i, vec3 l) {
    return !(HAS(SPOT_LIGHTS, i) && u_spot_cos[i] > -2.0 &&
             dot(-l, u_spot_direction[i]) < u_spot_cos[i]);
}
#endif

void main() {
#ifdef MASK_PASS
    // covered, and the lights the visible side faces (the loop's `side > 0.0` below, taken
    // per triangle in scene.vert), less the spots whose cone the pixel is outside
    uint lit = 1u | (gl_FrontFacing ? v_front_lights : v_back_lights);
#if LIGHTS > 0 && SPOT_LIGHTS != 0
    for (int i = 0; i < LIGHTS; ++i) {
        vec3 to_light = u_light[i].xyz - u_light[i].w * v_world;
        vec3 l = normalize(to_light);
        lit &= in_cone(i, l) ? 0xFFFFFFFFu : ~(2u << uint(i));
    }
#endif
#ifdef STENCIL_BITS
    gl_FragStencilRefARB = int(bitfieldReverse(lit) >> 24u);
#else
    f_lit_bits = lit;
#endif
#else
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 position = texelFetch(u_position, p, 0);
    // never 0 (uncovered) here: the pass is depth-tested to the covered pixels
    // (passes._only_where_covered), which is also why it has no branch for them (a per-pixel
    // branch costs llvmpipe 15% of the pass, taken or not)
    int surface = int(position.w);
    bool front = surface > 0;
    int t = abs(surface) - 1;
    vec4 normal_object = triangle_data[2 * t];
    vec3 normal = normal_object.xyz;
    int object = int(normal_object.w);
    vec3 corner = triangle_data[2 * t + 1].xyz;
    vec3 world = position.xyz;
#if LIGHTS > 1
    uint unshadowed = texelFetch(u_unshadowed, p, 0).r;
#else
    uint unshadowed = 0u;
#endif
#if LIGHTS > 0
    if (u_last_unshadowed) {
        unshadowed |= 1u << uint(LIGHTS - 1);
    }
#endif
    vec3 n = front ? normal : -normal;
#ifndef MASKS_ONLY
    vec3 kd = texelFetch(u_materials, ivec2(1, object), 0).rgb;
    vec4 ks = texelFetch(u_materials, ivec2(2, object), 0);
    vec3 v = normalize(u_eye - world);
    vec3 ka = texelFetch(u_materials, ivec2(0, object), 0).rgb;
#ifdef SURFACE
    vec3 base = texelFetch(u_tint, p, 0).rgb;
    int tex = int(texelFetch(u_materials, ivec2(3, object), 0).r);
    if (tex >= 0) {
        base *= base_colour(records[tex], texelFetch(u_uv, p, 0).xy);
    }
    ka *= base;
    kd *= base;
#endif
    vec3 colour = u_first_page ? ka * u_ambient : vec3(0.0);
#endif
    uint lit = u_first_page ? 1u : 0u;
#if LIGHTS > 0
    for (int i = 0; i < LIGHTS; ++i) {
        // Lit: unshadowed (outside this light's volumes), the light on the visible side
        // (n . l > 0: scene.vert's v_facing and phong.frag's test) and inside a spot's cone.
        // Every pixel evaluates the whole body and selects, rather than leaving the loop
        // early: on a CPU rasterizer (llvmpipe) `continue` under a per-pixel condition costs
        // a quarter of the pass; the selected values are the same bit for bit.
        precise float facing = dot(normal, u_light[i].xyz - u_light[i].w * corner);
        float side = front ? facing : -facing;
        vec3 to_light = u_light[i].xyz - u_light[i].w * world;
        vec3 l = normalize(to_light);
        bool on = (unshadowed & (1u << uint(i))) != 0u && side > 0.0 && in_cone(i, l);
        lit |= on ? 2u << uint(i) : 0u;
#ifndef MASKS_ONLY
        float n_dot_l = max(dot(n, l), 0.0);
        vec3 r = 2.0 * dot(n, l) * n - l;
        float r_dot_v = max(dot(r, v), 0.0);
        // x^0 is 1 (as in numpy), which GLSL's pow leaves undefined at x = 0
        float highlight = ks.a == 0.0 ? 1.0 : pow(r_dot_v, ks.a);
        float at_light = HAS(EMITTER_LIGHTS, i) && u_emitter_cosine[i] > 0.0
                         ? max(dot(-l, u_spot_direction[i]), 0.0) : 1.0;
        vec3 term = (kd * n_dot_l + ks.rgb * highlight) * u_radiance[i] * at_light;
        colour = on ? colour + term : colour;
#endif
    }
#endif
#if !defined(MASKS_ONLY) && defined(SRGB_OUT)
    // srgb.frag's encoding of the same float32 colour (keep the expressions identical): the
    // pixel the sRGB pass would have written from the stored colour
    vec3 c = clamp(colour, 0.0, 1.0);
    vec3 s = mix(1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, 12.92 * c,
                 vec3(lessThanEqual(c, vec3(0.0031308))));
    f_colour = vec4(floor(s * 255.0 + 0.5) / 255.0, 1.0);
#elif !defined(MASKS_ONLY)
    f_colour = vec4(colour, u_first_page ? 1.0 : 0.0);
#else
    f_colour = vec4(0.0);
#endif
    f_bits = float(lit);
#endif
}
