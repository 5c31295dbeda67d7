// The clip plane of the world seen in a mirror, pulled in with #include "clip.glsl".
// Every vertex shader writes gl_ClipDistance[0]: Mesa 22.3's llvmpipe clips by it even
// while GL_CLIP_DISTANCE0 is disabled, so "no plane" is (0, 0, 0, 1), which every point
// is in front of.
// World space, for positions relative to the view's origin as every vertex shader gets
// them (camera-relative rendering); what lies on its negative side is cut away.
uniform vec4 clip_plane;

float world_clip_distance;  // what clip_world wrote (a warp may cut further, warp.glsl)

void clip_world(vec4 world_position) {
    world_clip_distance = dot(clip_plane, world_position);
    gl_ClipDistance[0] = world_clip_distance;
}
