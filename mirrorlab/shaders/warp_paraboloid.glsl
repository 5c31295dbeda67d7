// The paraboloid warp of a hemisphere capture (Heidrich & Seidel 1998): stands in for
// warp.glsl in every program that draws a view warped by it (mirrorlab.views.Warp), in
// the vertex stage only, so a triangle's vertices land where the paraboloid puts them and
// its inside is filled between them in straight lines (what large triangles get wrong).
// The view's matrix takes a point to its eye space scaled so that the view reaches 1.
// The target is the square of mirrorlab.envmap.paraboloid_map's side: the hemisphere in
// front of the eye (eye -z) fills the disc of radius 1 / EXTENT, and the margin around
// it shows what lies past the rim.
const float PARABOLOID_EXTENT = 1.0625;  // mirrorlab.envmap.PARABOLOID_EXTENT
// Directions with eye z / |e| above this are cut away (gl_ClipDistance[0], after
// clip_world: a vertex shader calls project after it): past the rim
// as far as the square's corners (radius EXTENT sqrt 2: z = 0.386), not behind the eye,
// where the paraboloid runs off to infinity.
const float PARABOLOID_CUT = 0.4;

#ifdef WARP_VERTEX
vec4 project(mat4 to_eye, vec4 point) {
    vec3 e = (to_eye * point).xyz;
    float len = length(e);
    vec3 d = len > 1e-30 ? e / len : vec3(0.0, 0.0, -1.0);
    // with what clip.glsl wrote (a warped view's clip plane cuts nothing)
    gl_ClipDistance[0] = min(world_clip_distance, PARABOLOID_CUT - d.z);
    vec2 ab = d.xy / max(1.0 - d.z, 1e-6);
    // depth: the distance from the eye, linear from 0 to the view's reach
    return vec4(ab / PARABOLOID_EXTENT, 2.0 * len - 1.0, 1.0);
}
#else
// A target point's eye direction, continued past the rim: (2a, 2b, q - 1) / (1 + q) at
// paraboloid coordinates (a, b), q = a^2 + b^2; the matrix turns it into the world.
vec3 view_direction(mat3 eye_to_world, vec2 ndc) {
    vec2 ab = ndc * PARABOLOID_EXTENT;
    float q = dot(ab, ab);
    return eye_to_world * (vec3(2.0 * ab, q - 1.0) / (1.0 + q));
}
#endif
