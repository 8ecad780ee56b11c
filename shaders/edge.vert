#version 450 core
// One record of the edge buffer (Peciva et al. 2013): a welded edge (a, b) and up to
// MAX_OPPOSITE of its triangles' opposite vertices.  An edge with more triangles than one record
// holds is split over several records: multiplicity is additive.  Passed through to
// silhouette.geom.

in vec3 in_a;
in vec3 in_b;
in vec3 in_c0;
in vec3 in_c1;
in vec3 in_c2;
in vec3 in_c3;
in int in_count;  // how many of c0..c3 are used (1..4)

out vec3 v_a;
out vec3 v_b;
out vec3 v_c[4];
flat out int v_count;

void main() {
    v_a = in_a;
    v_b = in_b;
    v_c[0] = in_c0;
    v_c[1] = in_c1;
    v_c[2] = in_c2;
    v_c[3] = in_c3;
    v_count = in_count;
}
