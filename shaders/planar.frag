#version 450 core
// Planar projected shadows: keep a fragment only where the caster point it comes from makes a
// real shadow (planar.casts_shadow): 0 <= s, and s < 1 for a light at a finite position, i.e.
// the point lies between the light and the plane.  Anything else is an anti-shadow: a point
// below the plane, or beyond the light, which projects through the light onto the plane.
// Colour writes are off in the shadow pass: only the stencil records the shadow.

uniform vec4 u_light;

in float v_s;

layout(location = 0) out vec4 f_colour;

void main() {
    if (v_s < 0.0 || (u_light.w != 0.0 && v_s >= 1.0)) {
        discard;
    }
    f_colour = vec4(0.0, 0.0, 0.0, 1.0);
}
