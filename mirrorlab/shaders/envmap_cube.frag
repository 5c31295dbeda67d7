#version 330
// Cube map: the world-space reflection of the eye ray, per fragment, looked up in a
// samplerCube (static from six images, or captured live from the object's centre).
#include "common.glsl"
#include "view_ray.glsl"
in vec3 world_position;
in vec3 world_normal;

uniform samplerCube cube_map_texture;
uniform int output_mode;  // 0: colour; 1: the unit lookup direction

out vec4 frag_color;

void main() {
    vec3 u = view_ray(world_position);
    vec3 n = safe_normalize(world_normal, vec3(0.0));
    // r = 0 only for a fragment at the eye; cube_map(0) is the +X face's centre
    vec3 r = safe_normalize(u - 2.0 * dot(n, u) * n, vec3(1.0, 0.0, 0.0));
    if (output_mode == 1) {
        frag_color = vec4(r, 1.0);
    } else {
        frag_color = vec4(texture(cube_map_texture, r).rgb, 1.0);
    }
}
