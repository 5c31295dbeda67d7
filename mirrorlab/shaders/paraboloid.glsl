// The dual-paraboloid map (Heidrich & Seidel 1998), pulled in with
// #include "paraboloid.glsl" (after common.glsl): mirrorlab.envmap.paraboloid_map in GLSL
// and the lookup of its texture, the front side (rz >= 0) in the left half and the back
// in the right, each disc inside a margin of what lies past the rim.
uniform sampler2D paraboloid_texture;
const float PARABOLOID_EXTENT = 1.0625;  // mirrorlab.envmap.PARABOLOID_EXTENT

// (s, t) of a unit r on one side, continued past its rim (finite for either side)
vec2 paraboloid_side_st(vec3 r, bool front) {
    float below = max(1.0 + (front ? r.z : -r.z), 1e-6);
    vec2 ab = vec2(front ? -r.x : r.x, r.y) / (below * PARABOLOID_EXTENT);
    return 0.5 + 0.5 * ab;
}

// The map's colour over a pixel whose lookup direction changes by dx, dy to its
// neighbours: the side of the direction itself, its footprint measured on that side
// (continued past the rim, so no jump where a neighbour is on the other side).
vec3 map_color(vec3 look, vec3 dx, vec3 dy) {
    vec3 w = safe_normalize(look, vec3(0.0, 0.0, 1.0));
    bool front = w.z >= 0.0;
    vec2 st = paraboloid_side_st(w, front);
    vec2 step_x = paraboloid_side_st(safe_normalize(look + dx, w), front) - st;
    vec2 step_y = paraboloid_side_st(safe_normalize(look + dy, w), front) - st;
    vec2 half_width = vec2(0.5, 1.0);
    vec2 at = vec2((st.x + (front ? 0.0 : 1.0)) * 0.5, st.y);
    return textureGrad(paraboloid_texture, at, step_x * half_width, step_y * half_width).rgb;
}

// The lookup coordinates, for checks: where in the texture, ((side + s) / 2, t, 0).
vec3 map_coordinates(vec3 look) {
    vec3 w = safe_normalize(look, vec3(0.0));
    bool front = w.z >= 0.0;
    vec2 st = clamp(paraboloid_side_st(w, front), 0.0, 1.0);
    return vec3((st.x + (front ? 0.0 : 1.0)) * 0.5, st.y, 0.0);
}
