#version 450 core
// The ground truth's per-caster mark (shadowvol.raster.truth.count_casters): after one casting
// object's own volume count, drawn over the shadow's box where that count is not 0 (the
// stencil test is set by the pass), adds the object's bit: 2^(j mod 16) in channel j / 16 of an
// RGBA32F target (additive blending; distinct powers of two up to 2^15 sum exactly in float32,
// so four channels hold 64 objects).

uniform vec4 u_bit;

layout(location = 0) out vec4 f_casters;

void main() {
    f_casters = u_bit;
}
