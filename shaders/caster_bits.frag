#version 450 core
// After a group's per-caster counts (caster_count.frag), drawn over the shadow's box where a
// counted fragment landed (the stencil the counting pass set; truth.CasterCounts.add_bits):
// every caster whose counter is not 0 at the pixel sets its object's bit in the casters'
// 64-bit mask, two uint32 words (bits 0-31, 32-63) of an rg32ui image, cleared per light and
// added to by each group.  A counter of w bits holds its count + 2^(w-1) (truth.FIELD_BIAS).
//
// Defines: WORDS — the counter words of the group (a constant, so that the loop unrolls: on
// llvmpipe a loop over a uniform bound costs about twice as much).  Word w holds counters
// of u_width[w] bits (8, 16 or 32), slots u_first_slot[w] ..; slot k is object
// u_object_bits[k] (truth.counter_layout).

#ifndef WORDS
#define WORDS 1
#endif
#define SLOTS 32                // truth.CASTERS_PER_GROUP: the bits of `slots`

layout(early_fragment_tests) in;   // the stencil test decides before the shader runs

layout(r32ui, binding = 0) uniform uimage2DArray u_counts;
layout(rg32ui, binding = 1) uniform uimage2D u_casters;
uniform int u_width[WORDS];
uniform int u_first_slot[WORDS];
uniform uvec2 u_object_bits[SLOTS];  // slot k's object's bit in the two words

// Bit f set for each field f (of `width` bits) of v that is not its bias: a count not 0.
uint nonzero_fields(uint v, int width) {
    v ^= width == 8 ? 0x80808080u : (width == 16 ? 0x80008000u : 0u);  // truth.FIELD_BIAS
    uint t = v | (v >> 1u);      // fold every field's bits into its lowest bit
    t |= t >> 2u;
    t |= t >> 4u;
    if (width == 8) {
        // the lowest bits 0, 8, 16, 24 to bits 21..24: one product, no carries
        return (((t & 0x01010101u) * 0x00204081u) >> 21u) & 0xFu;
    }
    t |= t >> 8u;
    if (width == 16) {
        t &= 0x00010001u;
        return (t | (t >> 15u)) & 3u;
    }
    t |= t >> 16u;
    return t & 1u;
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    uint slots = 0u;
    for (int w = 0; w < WORDS; ++w) {
        uint v = imageLoad(u_counts, ivec3(p, w)).x;
        slots |= nonzero_fields(v, u_width[w]) << uint(u_first_slot[w]);
    }
    if (slots == 0u) {
        return;
    }
    uvec2 casters = imageLoad(u_casters, p).xy;
    while (slots != 0u) {
        casters |= u_object_bits[findLSB(slots)];
        slots &= slots - 1u;
    }
    imageStore(u_casters, p, uvec4(casters, 0u, 0u));
}
