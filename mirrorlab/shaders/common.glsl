// Shared helpers, pulled in with #include "common.glsl".

// v / |v|, or fallback where v has no length: never NaN.
vec3 safe_normalize(vec3 v, vec3 fallback) {
    float len = length(v);
    return len > 1e-30 ? v / len : fallback;
}

// mirrorlab.envmap.sphere_map: finite and in [0, 1] for every input.
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
