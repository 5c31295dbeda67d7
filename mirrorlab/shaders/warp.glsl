// How a view places what it draws on its target: the linear projection of an ordinary
// view, pulled in through project.glsl by the vertex shaders (WARP_VERTEX defined) and
// straight by the background's fragment shader. A warped view (mirrorlab.views.Warp)
// names a shader file of its own that stands in for this one in every program that
// draws it, defining the same two functions.
#ifdef WARP_VERTEX
// The clip-space position of an origin-relative point, given the view's matrix.
vec4 project(mat4 view_projection, vec4 point) {
    return view_projection * point;
}
#else
// The world direction of the view ray through a point (ndc) of the target, given the
// matrix that takes (ndc x, ndc y, 1) to it.
vec3 view_direction(mat3 ndc_to_direction, vec2 ndc) {
    return ndc_to_direction * vec3(ndc, 1.0);
}
#endif
