// Lambert lighting from LIGHT_COUNT directional lights (0 to MAX_LIGHTS) plus ambient,
// pulled in with #include "lighting.glsl" (mirrorlab.raytrace shades the same way).
// LIGHT_COUNT is defined by whoever builds the program (one program per count): a loop
// of known length is unrolled, where one bounded by a uniform costs llvmpipe about a
// seventh of a lab frame's time, in every fragment.
#define MAX_LIGHTS 4
uniform vec3 light_directions[MAX_LIGHTS];  // unit, from the surface towards the light
uniform vec3 light_colors[MAX_LIGHTS];      // colour times intensity
uniform float ambient;

vec3 lit(vec3 albedo, vec3 normal) {
    vec3 n = normalize(normal);
    vec3 light = vec3(ambient);
    for (int i = 0; i < LIGHT_COUNT; ++i) {
        light += light_colors[i] * max(dot(n, light_directions[i]), 0.0);
    }
    return albedo * light;
}
