// The vertex shaders' projection, pulled in with #include "project.glsl": the view's own
// (warp.glsl, or the file a warped view names in its place): project(matrix, point).
#define WARP_VERTEX
#include "warp.glsl"
