// What fixed-function GL_SPHERE_MAP texgen computes for a vertex, in a shader (the core
// profile has no texgen), pulled in with #include "texgen.glsl" after "common.glsl".
// The OpenGL specification's formula (2.1, section 2.12.4), in eye space:
//   u = p / |p|            the unit vector from the eye to the vertex p
//   r = u - 2 (n . u) n    n the unit eye-space normal (as with GL_NORMALIZE)
//   m = 2 sqrt(rx^2 + ry^2 + (rz + 1)^2)
//   s = rx / m + 1/2,  t = ry / m + 1/2
// Where GL's texgen gives NaN this stays finite, as mirrorlab.envmap.sphere_map_texgen
// does: a vertex at the eye has u = 0, so r = 0 and (1/2, 1/2); r = (0, 0, -1) (m = 0)
// gives the rim point (1, 1/2); a zero normal reflects nothing (r = u).
vec2 texgen_sphere_map(vec3 eye_position, vec3 eye_normal) {
    vec3 u = safe_normalize(eye_position, vec3(0.0));
    vec3 n = safe_normalize(eye_normal, vec3(0.0));
    vec3 r = u - 2.0 * dot(n, u) * n;
    float m = 2.0 * sqrt(r.x * r.x + r.y * r.y + (r.z + 1.0) * (r.z + 1.0));
    if (m <= 0.0) {
        return vec2(1.0, 0.5);
    }
    return r.xy / m + 0.5;
}
