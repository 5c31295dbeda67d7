#version 330
// A lit part, optionally textured.
#include "lighting.glsl"
in vec3 world_normal;
in vec2 surface_uv;

uniform vec3 color;
uniform bool use_texture;
uniform sampler2D surface;

out vec4 frag_color;

void main() {
    vec3 albedo = color;
    if (use_texture) {
        albedo *= texture(surface, surface_uv).rgb;
    }
    frag_color = vec4(lit(albedo, world_normal), 1.0);
}
