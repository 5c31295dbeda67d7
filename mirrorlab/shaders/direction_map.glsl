// A map looked up by the direction of the reflected view ray, per fragment: the body of
// the fragment shaders of the 2D maps of directions (envmap_octahedral.frag,
// envmap_paraboloid.frag), pulled in after the map's own file, which gives
// vec3 map_color(vec3 look, vec3 dx, vec3 dy) and vec3 map_coordinates(vec3 look).
// PARALLAX corrects a live map's lookup as envmap_cube.frag's does (parallax.glsl): 1 a
// box proxy, 2 a sphere proxy, 3 a distance search in the capture's depth cube.
in vec3 world_position;
in vec3 world_normal;

uniform samplerCube background_map;  // a distance search's rays that meet nothing
// 0: colour; 1: the lookup coordinates (map_coordinates: where in the texture, (s, t,
// 0)), alpha 1 for a lookup in the
// map and 0 for one in the background map; 2: the reflected ray's origin (world); 3: its
// unit direction (before any parallax correction)
uniform int output_mode;
uniform vec3 view_origin;  // world_position is relative to it (camera-relative rendering)

out vec4 frag_color;

void main() {
    vec3 u = view_ray(world_position);
    vec3 n = safe_normalize(world_normal, vec3(0.0));
    // r = 0 only for a fragment at the eye
    vec3 r = safe_normalize(u - 2.0 * dot(n, u) * n, vec3(1.0, 0.0, 0.0));
    bool background = false;  // a distance search's ray that meets nothing it saw
#if PARALLAX == 1
    vec3 look = box_lookup(world_position, r);
#elif PARALLAX == 2
    vec3 look = sphere_lookup(world_position, r);
#elif PARALLAX == 3
    vec3 look = distance_lookup(world_position, r, background);
#else
    vec3 look = r;
#endif
    // The footprint from the corrected direction's screen-space change, but never a
    // larger one than the plain reflection's (envmap_cube.frag says why).
    vec3 look_dx = dFdx(look);
    vec3 look_dy = dFdy(look);
    vec3 plain_dx = dFdx(r);
    vec3 plain_dy = dFdy(r);
    vec3 dx = dot(look_dx, look_dx) <= dot(plain_dx, plain_dx) ? look_dx : plain_dx;
    vec3 dy = dot(look_dy, look_dy) <= dot(plain_dy, plain_dy) ? look_dy : plain_dy;
#if PARALLAX == 3
    vec3 far = texture(background_map, r).rgb;  // sampled in uniform control flow
#else
    vec3 far = vec3(0.0);
#endif
    if (output_mode == 1) {
        frag_color = vec4(map_coordinates(look), background ? 0.0 : 1.0);
    } else if (output_mode == 2) {
        frag_color = vec4(world_position + view_origin, 1.0);
    } else if (output_mode == 3) {
        frag_color = vec4(r, 1.0);
    } else {
        vec3 color = map_color(look, dx, dy);
        frag_color = vec4(background ? far : color, 1.0);
    }
}
