#version 330
// Cube map: the world-space reflection of the eye ray, per fragment, looked up in a
// samplerCube (static from six images, or captured live from the object's centre).
in vec3 world_position;
in vec3 world_normal;

uniform samplerCube cube_map_texture;
uniform vec3 eye_world;  // the viewer's position, world units
uniform int output_mode;  // 0: colour; 1: the unit lookup direction

out vec4 frag_color;

vec3 safe_normalize(vec3 v, vec3 fallback) {
    float len = length(v);
    return len > 1e-30 ? v / len : fallback;
}

void main() {
    vec3 u = safe_normalize(world_position - eye_world, vec3(0.0));
    vec3 n = safe_normalize(world_normal, vec3(0.0));
    // r = 0 only for a fragment at the eye; cube_map(0) is the +X face's centre
    vec3 r = safe_normalize(u - 2.0 * dot(n, u) * n, vec3(1.0, 0.0, 0.0));
    if (output_mode == 1) {
        frag_color = vec4(r, 1.0);
    } else {
        frag_color = vec4(texture(cube_map_texture, r).rgb, 1.0);
    }
}
