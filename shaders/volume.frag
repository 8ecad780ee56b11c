#version 450 core
// Shadow-volume polygons.  While counting into the stencil, colour writes are off and this
// output goes nowhere; the teaching view draws the same polygons with their role's colour.

uniform vec4 u_colour;

layout(location = 0) out vec4 f_colour;

void main() {
    f_colour = u_colour;
}
