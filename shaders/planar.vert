#version 450 core
// Planar projected shadows (Blinn 1988): a caster's triangles squashed from the light onto the
// receiving plane by the matrix of shadowvol/raster/planar.py, drawn as the shadow.
//
// gl_Position is NOT divided by the projection's w: GL interpolates perspective-correctly in
// the homogeneous clip coordinates it is given, so a fragment's varyings are the barycentric
// interpolation over the ORIGINAL (unprojected) triangle.  That makes v_s below exact at every
// fragment, and the anti-shadow test per fragment rather than per vertex.

uniform mat4 u_view_proj_planar;  // (world -> clip) . M, formed in float64, rounded once
uniform vec4 u_plane;             // P = (n, d), unit n: points x with n . x + d = 0
uniform vec4 u_light;             // (position, 1) for a point or spot light, (-direction, 0)
                                  // for a directional light: the homogeneous light L

in vec3 in_position;              // world space, the scene soup's vertex

out float v_s;                    // s = (P . X) / (P . L), see planar.casts_shadow

void main() {
    vec4 x = vec4(in_position, 1.0);
    gl_Position = u_view_proj_planar * x;
    v_s = dot(u_plane, x) / dot(u_plane, u_light);
}
