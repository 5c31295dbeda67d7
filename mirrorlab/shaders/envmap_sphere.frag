#version 330
// Sphere map, per vertex (interpolated texgen coordinates) or per fragment (the
// reflection recomputed from the interpolated eye-space position and normal).
#include "common.glsl"
in vec3 eye_position;
in vec3 eye_normal;
in vec2 vertex_sphere_st;

uniform sampler2D sphere_map_texture;
uniform bool per_vertex;
uniform int output_mode;  // 0: colour; 1: the lookup coordinates (s, t, 0)
uniform bool orthographic;  // an orthographic view looks along eye -z everywhere

out vec4 frag_color;

void main() {
    vec2 st;
    if (per_vertex) {
        st = clamp(vertex_sphere_st, 0.0, 1.0);
    } else {
        vec3 u = orthographic ? vec3(0.0, 0.0, -1.0) : safe_normalize(eye_position, vec3(0.0));
        vec3 n = safe_normalize(eye_normal, vec3(0.0));
        st = sphere_map(u - 2.0 * dot(n, u) * n);
    }
    if (output_mode == 1) {
        frag_color = vec4(st, 0.0, 1.0);
    } else {
        frag_color = vec4(texture(sphere_map_texture, st).rgb, 1.0);
    }
}
