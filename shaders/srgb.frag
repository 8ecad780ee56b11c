#version 450 core
// Linear RGB -> 8-bit sRGB (IEC 61966-2-1, as shadowvol.io.encode_srgb), rows flipped so that
// the read-back comes out row 0 at the top.  The stored value is k / 255 for the rounded code
// k, which every conformant float -> UNORM8 conversion maps back to k.

uniform sampler2D u_colour;

layout(location = 0) out vec4 f_srgb;

void main() {
    ivec2 size = textureSize(u_colour, 0);
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec3 c = clamp(texelFetch(u_colour, ivec2(p.x, size.y - 1 - p.y), 0).rgb, 0.0, 1.0);
    vec3 s = mix(1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, 12.92 * c,
                 vec3(lessThanEqual(c, vec3(0.0031308))));
    f_srgb = vec4(floor(s * 255.0 + 0.5) / 255.0, 1.0);
}
