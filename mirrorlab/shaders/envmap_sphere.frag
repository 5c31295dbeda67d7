#version 330
// Sphere map, per vertex (interpolated texgen coordinates) or per fragment (the
// reflection recomputed from the interpolated eye-space position and normal).
in vec3 eye_position;
in vec3 eye_normal;
in vec2 vertex_sphere_st;

uniform sampler2D sphere_map_texture;
uniform bool per_vertex;
uniform int output_mode;  // 0: colour; 1: the lookup coordinates (s, t, 0)

out vec4 frag_color;

vec3 safe_normalize(vec3 v, vec3 fallback) {
    float len = length(v);
    return len > 1e-30 ? v / len : fallback;
}

vec2 sphere_map(vec3 r) {
    vec3 w = safe_normalize(r, vec3(0.0));
    float rho2 = dot(w.xy, w.xy);
    float z_plus_one = w.z >= 0.0 ? 1.0 + w.z : rho2 / (1.0 - w.z);
    float half_m = sqrt(rho2 + z_plus_one * z_plus_one);
    if (half_m <= 0.0) {
        return vec2(1.0, 0.5);
    }
    return clamp(0.5 + 0.5 * w.xy / half_m, 0.0, 1.0);
}

void main() {
    vec2 st;
    if (per_vertex) {
        st = clamp(vertex_sphere_st, 0.0, 1.0);
    } else {
        vec3 u = safe_normalize(eye_position, vec3(0.0));
        vec3 n = safe_normalize(eye_normal, vec3(0.0));
        st = sphere_map(u - 2.0 * dot(n, u) * n);
    }
    if (output_mode == 1) {
        frag_color = vec4(st, 0.0, 1.0);
    } else {
        frag_color = vec4(texture(sphere_map_texture, st).rgb, 1.0);
    }
}
