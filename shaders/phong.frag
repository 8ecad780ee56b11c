#version 450 core
// One light's direct Phong term, added where the stencil count is 0 (the stencil test and the
// depth test EQUAL are set by the pass).  The same terms as the ray tracer's direct light:
// kd max(n.l, 0) + ks max(r.v, 0)^shininess, times the light's radiance; no attenuation; the
// face normal flipped toward the viewer; a spot light only inside its cone; an area light's
// sample is a 90-degree spot light, also weighted by its cosine at the light.  Linear RGB.

uniform sampler2D u_materials;  // row = object: texel 0 ka, 1 kd, 2 (ks, shininess)
uniform vec4 u_light;           // (position, 1) or (-direction, 0)
uniform vec3 u_radiance;
uniform vec3 u_eye;
uniform vec3 u_spot_direction;  // unit; used when u_spot_cos > -2
uniform float u_spot_cos;       // cos of the cone's half-angle; -2 for no cone
uniform float u_emitter_cosine; // 1: a one-sided area light's sample, weighted by the cosine at
                                // the light, max(-l . u_spot_direction, 0); 0: no weight

in vec3 v_world;
flat in vec3 v_normal;
flat in float v_facing;
flat in int v_object;

layout(location = 0) out vec4 f_colour;
layout(location = 1) out float f_lit;

void main() {
    // gl_FrontFacing is exactly "the wound normal points at the eye" for this rasterized
    // triangle, so it flips the normal toward the viewer without a per-pixel dot product.
    vec3 n = gl_FrontFacing ? v_normal : -v_normal;
    float side = gl_FrontFacing ? v_facing : -v_facing;
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
    float at_light = u_emitter_cosine > 0.0 ? max(dot(-l, u_spot_direction), 0.0) : 1.0;
    f_colour = vec4((kd * n_dot_l + ks.rgb * highlight) * u_radiance * at_light, 0.0);
    f_lit = 1.0;
}
