#version 450 core
// GPU silhouettes: the multiplicity of one edge record and its side quads.
// m = sum over the record's triangles (a, b, c) of tri_sign(a, b, c); emit |m| quads extruded
// to infinity along the edge as the light-facing triangles run it, s -> e = a -> b when m > 0,
// b -> a when m < 0, wound to face out of the volume (see shadowvol/raster/silhouettes.py).

layout(points) in;
layout(triangle_strip, max_vertices = 24) out;  // 4 opposite vertices -> at most 4 quads

uniform mat4 u_view_proj;
uniform vec4 u_light;  // (position, 1) or (-direction, 0)
// Defines: ZPASS_CLIP — also write the distances to the z-pass clip box (see
// volume_side.vert: a separate program for z-pass draws only).
#ifdef ZPASS_CLIP
uniform vec4 u_clip_planes[6];  // (n, d), n.x + d w >= 0 inside
out float gl_ClipDistance[6];
#endif

in vec3 v_a[];
in vec3 v_b[];
in vec3 v_c[][4];
flat in int v_count[];

invariant gl_Position;

void emit(vec4 p) {
    gl_Position = u_view_proj * p;
#ifdef ZPASS_CLIP
    for (int i = 0; i < 6; ++i) {
        gl_ClipDistance[i] = dot(u_clip_planes[i], p);
    }
#endif
    EmitVertex();
}

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
    int m = 0;
    for (int i = 0; i < v_count[0]; ++i) {
        m += tri_sign(v_a[0], v_b[0], v_c[0][i], u_light);
    }
    vec3 s = m > 0 ? v_a[0] : v_b[0];
    vec3 e = m > 0 ? v_b[0] : v_a[0];
    vec4 s_inf = vec4(s * u_light.w - u_light.xyz, 0.0);
    vec4 e_inf = vec4(e * u_light.w - u_light.xyz, 0.0);
    for (int k = 0; k < abs(m); ++k) {
        // the quad e -> s -> s_inf -> e_inf as the CPU path draws it (quads_to_triangles):
        // triangles (e, s, s_inf) and (e, s_inf, e_inf), the same corners in the same order,
        // so that both paths rasterize the same triangles
        emit(vec4(e, 1.0));
        emit(vec4(s, 1.0));
        emit(s_inf);
        EndPrimitive();
        emit(vec4(e, 1.0));
        emit(s_inf);
        emit(e_inf);
        EndPrimitive();
    }
}
