#version 450 core
// One light's direct Phong term, added where the stencil count is 0 (the stencil test, and in
// the forward pass the depth test EQUAL, are set by the pass).  The same terms as the ray
// tracer's direct light: kd max(n.l, 0) + ks max(r.v, 0)^shininess, times the light's radiance;
// no attenuation; the face normal flipped toward the viewer; a spot light only inside its cone.
// Linear RGB.
//
// DEFERRED: drawn over the whole screen (fullscreen.vert) after the geometry pass
// (gbuffer.frag); the surface's world position and triangle come from the G-buffer and its
// flat values (normal, first corner, object) from the per-triangle storage buffer, the same
// float32 numbers the forward pass gets as flat vertex attributes, combined by the same
// expressions.  The lit bit is 2^(i+1) for the i-th light of the frame (added by blending).

uniform sampler2D u_materials;  // row = object: texel 0 ka, 1 kd, 2 (ks, shininess)
uniform vec4 u_light;           // (position, 1) or (-direction, 0)
uniform vec3 u_radiance;
uniform vec3 u_eye;
uniform vec3 u_spot_direction;  // unit; used when u_spot_cos > -2
uniform float u_spot_cos;       // cos of the cone's half-angle; -2 for no cone

#ifdef DEFERRED
uniform sampler2D u_position;   // world position (xyz) of the visible surface
uniform isampler2D u_surface;   // +-(triangle + 1), negative for a back face; 0: uncovered
uniform float u_bit;            // this light's lit bit, 2^(i+1)
layout(std430, binding = 0) readonly buffer Triangles {
    vec4 triangle_data[];       // per triangle: (unit normal, object), (first corner, 0)
};
#else
in vec3 v_world;
flat in vec3 v_normal;
flat in float v_facing;
flat in int v_object;
#endif

layout(location = 0) out vec4 f_colour;
layout(location = 1) out float f_lit;

void main() {
#ifdef DEFERRED
    ivec2 p = ivec2(gl_FragCoord.xy);
    int surface = texelFetch(u_surface, p, 0).r;
    if (surface == 0) {
        discard;  // no geometry at this pixel
    }
    bool front = surface > 0;
    int t = abs(surface) - 1;
    vec4 normal_object = triangle_data[2 * t];
    vec3 v_normal = normal_object.xyz;
    int v_object = int(normal_object.w);
    vec3 in_corner = triangle_data[2 * t + 1].xyz;
    // scene.vert's v_facing, from the same flat inputs
    float v_facing = dot(v_normal, u_light.xyz - u_light.w * in_corner);
    vec3 v_world = texelFetch(u_position, p, 0).xyz;
#else
    // gl_FrontFacing is exactly "the wound normal points at the eye" for this rasterized
    // triangle, so it flips the normal toward the viewer without a per-pixel dot product.
    bool front = gl_FrontFacing;
#endif
    vec3 n = front ? v_normal : -v_normal;
    float side = front ? v_facing : -v_facing;
    if (side <= 0.0) {
        discard;  // the light is behind the visible side: not lit (n . l <= 0)
    }
    vec3 to_light = u_light.xyz - u_light.w * v_world;
    vec3 l = normalize(to_light);
    if (u_spot_cos > -2.0 && dot(-l, u_spot_direction) < u_spot_cos) {
        discard;  // outside the spot's cone
    }
    vec3 kd = texelFetch(u_materials, ivec2(1, v_object), 0).rgb;
    vec4 ks = texelFetch(u_materials, ivec2(2, v_object), 0);
    vec3 v = normalize(u_eye - v_world);
    float n_dot_l = max(dot(n, l), 0.0);
    vec3 r = 2.0 * dot(n, l) * n - l;
    float r_dot_v = max(dot(r, v), 0.0);
    // x^0 is 1 (as in numpy), which GLSL's pow leaves undefined at x = 0
    float highlight = ks.a == 0.0 ? 1.0 : pow(r_dot_v, ks.a);
    f_colour = vec4((kd * n_dot_l + ks.rgb * highlight) * u_radiance, 0.0);
#ifdef DEFERRED
    f_lit = u_bit;
#else
    f_lit = 1.0;
#endif
}
