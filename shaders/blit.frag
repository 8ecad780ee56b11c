#version 450 core
// The viewer's blit: the composed picture, one texel per window pixel (texelFetch: no
// filtering, so the window shows exactly the pixels it was given).  Row 0 of the texture is the
// picture's top row, uploaded as is; the window's y runs up, hence the flip.

uniform sampler2D u_picture;

in vec2 v_uv;
out vec4 f_colour;

void main() {
    ivec2 size = textureSize(u_picture, 0);
    ivec2 texel = ivec2(gl_FragCoord.x, float(size.y) - gl_FragCoord.y);
    f_colour = vec4(texelFetch(u_picture, texel, 0).rgb, 1.0);
}
