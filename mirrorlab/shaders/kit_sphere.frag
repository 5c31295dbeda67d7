#version 330 core
// The sphere-map lab's cone, per fragment: the student's reflect_eye and sphere_map_st
// (declared below) pick the texel of the sphere map. The cone is tinted gold, so that the
// shader's cone and the texgen cone (untinted) tell apart in the frame: which side each
// is on is visible, as the variant's side must be.
in vec3 eye_position;
in vec3 eye_normal;

uniform sampler2D sphere_map;
uniform int mode;  // 0 colour; 1 the student's r; 2 u; 3 n; 4 the student's (s, t) of the kit's r

out vec4 frag_color;

const vec3 SHADER_TINT = vec3(1.0, 0.8, 0.45);

// STUDENT CODE: the student's functions, compiled alone and linked to this main
vec3 reflect_eye(vec3 u, vec3 n);
vec2 sphere_map_st(vec3 r);

void main() {
    vec3 u = normalize(eye_position);
    vec3 n = normalize(eye_normal);
    if (mode == 1) {
        frag_color = vec4(reflect_eye(u, n), 1.0);
    } else if (mode == 2) {
        frag_color = vec4(u, 1.0);
    } else if (mode == 3) {
        frag_color = vec4(n, 1.0);
    } else if (mode == 4) {
        frag_color = vec4(sphere_map_st(u - 2.0 * dot(n, u) * n), 0.0, 1.0);
    } else {
        vec3 texel = texture(sphere_map, sphere_map_st(reflect_eye(u, n))).rgb;
        frag_color = vec4(texel * SHADER_TINT, 1.0);
    }
}
