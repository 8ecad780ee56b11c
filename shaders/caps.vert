#version 450 core
// GPU caps for z-fail, without a geometry shader: every vertex carries its triangle's three
// corners, computes the triangle's orientation against the light (tri_sign, as wound) and keeps
// the triangle only if it equals u_cap_sign; otherwise all three vertices go to one point
// outside the clip volume and the triangle is dropped.  The caller draws sign +1 and -1
// separately and sets the front face so that each cap faces out of its volume.
//
// Why not a geometry shader: on llvmpipe, a triangle passed through a geometry shader with its
// gl_Position unchanged does NOT rasterize to bit-identical depths, and the near cap must tie
// exactly with the depth pass (see shadowvol/raster/volumes.py).  A vertex shader computing
// gl_Position with the same invariant expression as scene.vert does.
//
// Defines: FAR_CAP — project the triangle to infinity (V -> (V - L, 0)) instead of drawing it
// in place.

uniform mat4 u_view_proj;
uniform vec4 u_light;  // (position, 1) or (-direction, 0)
uniform int u_cap_sign;

in vec3 in_position;
in vec3 in_corner;   // v0, v1, v2 of this vertex's triangle, as wound
in vec3 in_corner1;
in vec3 in_corner2;

invariant gl_Position;

// --- tri_sign: keep identical in silhouette.geom and caps.vert -------------------------------
// The orientation of triangle (p, q, r) against the light, +1 / -1 / 0, computed on the three
// points sorted into one canonical (lexicographic) order and corrected by the permutation's
// parity.  Every caller that sees the same three float32 points therefore evaluates the very
// same expression and gets the same sign: an edge record and the cap of the same triangle never
// disagree, even when the light is nearly in the triangle's plane.  `precise` forbids the
// compiler from contracting or reordering it differently in the two shaders.
bool lex_less(vec3 x, vec3 y) {
    return x.x < y.x || (x.x == y.x && (x.y < y.y || (x.y == y.y && x.z < y.z)));
}

int tri_sign(vec3 p, vec3 q, vec3 r, vec4 light) {
    int parity = 1;
    vec3 t;
    if (lex_less(q, p)) { t = p; p = q; q = t; parity = -parity; }
    if (lex_less(r, q)) { t = q; q = r; r = t; parity = -parity; }
    if (lex_less(q, p)) { t = p; p = q; q = t; parity = -parity; }
    precise vec3 n = cross(q - p, r - p);
    precise float d = dot(n, light.xyz - light.w * p);
    return d > 0.0 ? parity : (d < 0.0 ? -parity : 0);
}
// ---------------------------------------------------------------------------------------------

void main() {
    if (tri_sign(in_corner, in_corner1, in_corner2, u_light) != u_cap_sign) {
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);  // outside: x > w
        return;
    }
#ifdef FAR_CAP
    gl_Position = u_view_proj * vec4(in_position * u_light.w - u_light.xyz, 0.0);
#else
    gl_Position = u_view_proj * vec4(in_position, 1.0);
#endif
}
