#version 330
// A lit part, optionally textured.
#include "lighting.glsl"
in vec3 world_normal;
in vec2 surface_uv;

uniform mat4 part;  // column 3: the part's colour, and 1 if it wears its texture
uniform sampler2D surface;

out vec4 frag_color;

void main() {
    vec3 albedo = part[3].rgb;
    if (part[3].a > 0.5) {
        albedo *= texture(surface, surface_uv).rgb;
    }
    frag_color = vec4(lit(albedo, world_normal), 1.0);
}
