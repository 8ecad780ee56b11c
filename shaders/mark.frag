#version 450 core
// After a light's volume pass, drawn over the whole screen with a colour logic op into the
// unsigned-integer bits (the stencil test and the op are set by the pass):
// - the deferred frame's marks: OR where the stencil count is 0, adding the light's bit 2^i to
//   the unshadowed bits (shade.frag turns them into lit bits and light);
// - the mask pass's clears: AND-NOT where the count is not 0, removing the light's lit bit
//   2^(i + 1) that the geometry pass set (shade.frag's MASK_PASS).

uniform uint u_bit;

layout(location = 0) out uint f_bits;

void main() {
    f_bits = u_bit;
}
