#version 330
// Cube map: the world-space reflection of the eye ray, per fragment, looked up in a
// samplerCube (static from six images, or captured live from the object's centre).
// PARALLAX (a #define; 0 when not given) corrects a live map's lookup for nearby
// surroundings: 1 a box proxy, 2 a sphere proxy, 3 a distance search (parallax.glsl).
#ifndef PARALLAX
#define PARALLAX 0
#endif
#include "common.glsl"
#include "view_ray.glsl"
#include "parallax.glsl"
in vec3 world_position;
in vec3 world_normal;

uniform samplerCube cube_map_texture;
uniform samplerCube background_map;  // a distance search's rays that meet nothing
// 0: colour; 1: the unit lookup direction, alpha 1 for a lookup in the cube map and 0
// for one in the background map; 2: the reflected ray's origin (world); 3: its unit
// direction (before any parallax correction)
uniform int output_mode;
uniform vec3 view_origin;  // world_position is relative to it (camera-relative rendering)

out vec4 frag_color;

void main() {
    vec3 u = view_ray(world_position);
    vec3 n = safe_normalize(world_normal, vec3(0.0));
    // r = 0 only for a fragment at the eye; cube_map(0) is the +X face's centre
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
    if (output_mode == 1) {
        frag_color = vec4(look, background ? 0.0 : 1.0);
    } else if (output_mode == 2) {
        frag_color = vec4(world_position + view_origin, 1.0);
    } else if (output_mode == 3) {
        frag_color = vec4(r, 1.0);
    } else {
#if PARALLAX == 0
        frag_color = vec4(texture(cube_map_texture, look).rgb, 1.0);
#else
        // The mip level from the corrected direction's screen-space change, but never a
        // larger footprint than the plain reflection's: where the correction jumps (an
        // object's edge in a distance search) its difference spans the jump, and the
        // coarsest level would smear a band along it. Elsewhere a correction moves the
        // lookup less than the plain reflection moves.
        vec3 look_dx = dFdx(look);
        vec3 look_dy = dFdy(look);
        vec3 plain_dx = dFdx(r);
        vec3 plain_dy = dFdy(r);
        vec3 dx = dot(look_dx, look_dx) <= dot(plain_dx, plain_dx) ? look_dx : plain_dx;
        vec3 dy = dot(look_dy, look_dy) <= dot(plain_dy, plain_dy) ? look_dy : plain_dy;
        vec3 color = textureGrad(cube_map_texture, look, dx, dy).rgb;
#if PARALLAX == 3
        vec3 far = texture(background_map, r).rgb;  // sampled in uniform control flow
        color = background ? far : color;
#endif
        frag_color = vec4(color, 1.0);
#endif
    }
}
