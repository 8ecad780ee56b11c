#version 450 core
// The ground truth's per-caster counts (shadowvol.raster.truth.CasterCounts).  Drawn with the
// shadow-volume programs' own vertex stages, over the same side quads and caps, in the same
// z-pass and z-fail groups as the stencil count, after the frame: each fragment adds to ITS
// caster's counter what the stencil adds to the one count of all casters.  z-pass
// (u_front_step = +1) counts the faces that pass the depth test, front +1 and back -1; z-fail
// (u_front_step = -1) is drawn with the complementary depth test, so it counts the faces that
// fail the stencil pass's, back +1 and front -1.  So each counter ends as that caster's own
// stencil count, and they sum to the stencil's.  The stencil marks where any of these
// fragments lands (stencil.caster_touching), and caster_bits.frag's pass runs only there.
//
// A counter is the bit field [u_shift, u_shift + width) of word u_word of an r32ui image
// array (several casters share a word; truth.counter_layout), cleared to 2^(width-1).  The
// additions are modulo 2^32 and commute, so the word ends as that plus the sum of
// count << shift over its casters, whatever the order of the fragments; each field then holds
// its caster's count + 2^(width-1) exactly while the count lies in [-2^(width-1), 2^(width-1))
// (truth.CasterCounts).
//
// early_fragment_tests: the depth test runs before this shader, so only the fragments that
// pass it count (without it a shader with side effects runs for every fragment, and the
// depth test only decides what is written to the framebuffer; colour and depth writes are
// off).

layout(early_fragment_tests) in;

layout(r32ui, binding = 0) uniform uimage2DArray u_counts;
uniform int u_word;
uniform int u_shift;
uniform int u_front_step;

void main() {
    int step = gl_FrontFacing ? u_front_step : -u_front_step;
    imageAtomicAdd(u_counts, ivec3(gl_FragCoord.xy, u_word), uint(step) << uint(u_shift));
}
