#version 330
// The environment-mapped object: world- and eye-space position and normal for the
// per-fragment methods, and the per-vertex sphere-map coordinates (what GL_SPHERE_MAP
// texgen computes) for the per-vertex method. The view matrix must be rigid, so that
// its upper 3x3 also carries normals from world to eye space.
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;

uniform mat4 model;
uniform mat4 view;
uniform mat4 projection;
uniform mat3 normal_matrix;  // inverse transpose of the model's upper 3x3

out vec3 world_position;
out vec3 world_normal;
out vec3 eye_position;
out vec3 eye_normal;
out vec2 vertex_sphere_st;

vec3 safe_normalize(vec3 v, vec3 fallback) {
    float len = length(v);
    return len > 1e-30 ? v / len : fallback;
}

// mirrorlab.envmap.sphere_map in GLSL: finite and in [0, 1] for every input.
vec2 sphere_map(vec3 r) {
    vec3 w = safe_normalize(r, vec3(0.0));  // r = 0 lands on the centre
    float rho2 = dot(w.xy, w.xy);
    // 1 + rz loses all its digits near rz = -1; rho^2 / (1 - rz) keeps them
    float z_plus_one = w.z >= 0.0 ? 1.0 + w.z : rho2 / (1.0 - w.z);
    float half_m = sqrt(rho2 + z_plus_one * z_plus_one);
    if (half_m <= 0.0) {
        return vec2(1.0, 0.5);  // exactly (0, 0, -1): the whole rim; pick one point
    }
    return clamp(0.5 + 0.5 * w.xy / half_m, 0.0, 1.0);
}

void main() {
    vec4 world = model * vec4(position, 1.0);
    vec4 eye = view * world;
    world_position = world.xyz;
    world_normal = normal_matrix * normal;
    eye_position = eye.xyz;
    eye_normal = mat3(view) * world_normal;
    vec3 u = safe_normalize(eye.xyz, vec3(0.0));          // a vertex at the eye: r = 0
    vec3 n = safe_normalize(eye_normal, vec3(0.0));       // no normal: r = u
    vertex_sphere_st = sphere_map(u - 2.0 * dot(n, u) * n);
    gl_Position = projection * eye;
}
