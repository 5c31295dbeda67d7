#version 330 core
// The cube-map lab's sphere: the world-space reflection of the eye ray goes through the
// student's cube_face and cube_face_st (declared below); the kit turns that face and
// (s, t) back into a direction by the OpenGL table and samples the cube map there, so a
// wrong face or wrong coordinates show as a wrong reflection.
in vec3 world_position;
in vec3 world_normal;

uniform samplerCube cube_map;
uniform vec3 eye_world;
uniform int mode;  // 0 colour; 1 (face, s, t) of the student's functions; 2 r

out vec4 frag_color;

// STUDENT CODE: the student's functions, compiled alone and linked to this main
int cube_face(vec3 r);
vec2 cube_face_st(vec3 r, int face);

vec3 face_direction(int face, vec2 st) {
    float sc = 2.0 * st.x - 1.0;
    float tc = 2.0 * st.y - 1.0;
    if (face == 0) return vec3(1.0, -tc, -sc);
    if (face == 1) return vec3(-1.0, -tc, sc);
    if (face == 2) return vec3(sc, 1.0, tc);
    if (face == 3) return vec3(sc, -1.0, -tc);
    if (face == 4) return vec3(sc, -tc, 1.0);
    return vec3(-sc, -tc, -1.0);
}

void main() {
    vec3 u = normalize(world_position - eye_world);
    vec3 n = normalize(world_normal);
    vec3 r = u - 2.0 * dot(n, u) * n;
    int face = cube_face(r);
    vec2 st = cube_face_st(r, face);
    if (mode == 1) {
        frag_color = vec4(float(face), st, 1.0);
    } else if (mode == 2) {
        frag_color = vec4(r, 1.0);
    } else {
        vec3 direction = face_direction(clamp(face, 0, 5), clamp(st, 0.0, 1.0));
        frag_color = vec4(texture(cube_map, direction).rgb, 1.0);
    }
}
