#version 450 core
// After a light's volume pass, drawn over the whole screen where the stencil count is 0 (the
// stencil test is set by the pass): adds the light's bit 2^i to the unshadowed bits (additive
// blending; distinct powers of two sum exactly in float32 up to 2^24).  shade.frag turns them
// into lit bits and light.

uniform float u_bit;

layout(location = 0) out float f_unshadowed;

void main() {
    f_unshadowed = u_bit;
}
