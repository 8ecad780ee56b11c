#version 450 core
// Side quads of shadow volumes built on the CPU: homogeneous world positions, w = 1 on the
// silhouette edge and w = 0 for its copy extruded to infinity, away from the light.

//
// Defines: ZPASS_CLIP — also write the distances to the z-pass clip box
// (shadowvol/raster/methods.py zpass_clip_planes), for z-pass draws only.  A separate program, not
// a switch: on llvmpipe a vertex shader that writes gl_ClipDistance changes how the z-fail
// draws (depth clamp on, as they then were) are clipped even with every GL_CLIP_DISTANCEi
// disabled (checked: 500 interior mismatches on scenes/cage.toml under z-fail).

uniform mat4 u_view_proj;
#ifdef ZPASS_CLIP
uniform vec4 u_clip_planes[6];  // (n, d), n.x + d w >= 0 inside
out float gl_ClipDistance[6];
#endif

in vec4 in_position;

invariant gl_Position;

void main() {
    gl_Position = u_view_proj * in_position;
#ifdef ZPASS_CLIP
    for (int i = 0; i < 6; ++i) {
        gl_ClipDistance[i] = dot(u_clip_planes[i], in_position);
    }
#endif
}
