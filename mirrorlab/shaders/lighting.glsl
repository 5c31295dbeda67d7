// Lambert lighting from up to MAX_LIGHTS directional lights plus ambient, pulled in with
// #include "lighting.glsl" (mirrorlab.raytrace shades the same way).
#define MAX_LIGHTS 4
uniform int light_count;
uniform vec3 light_directions[MAX_LIGHTS];  // unit, from the surface towards the light
uniform vec3 light_colors[MAX_LIGHTS];      // colour times intensity
uniform float ambient;

vec3 lit(vec3 albedo, vec3 normal) {
    vec3 n = normalize(normal);
    vec3 light = vec3(ambient);
    for (int i = 0; i < light_count; ++i) {
        light += light_colors[i] * max(dot(n, light_directions[i]), 0.0);
    }
    return albedo * light;
}
