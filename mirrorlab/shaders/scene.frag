#version 330
// A lit part, optionally textured. The texture is read for every fragment and used where
// the part wears it (one fetch and a select runs faster on llvmpipe, which shades pixels
// in SIMD batches, than a branch).
#include "lighting.glsl"
in vec3 world_normal;
in vec2 surface_uv;
flat in vec4 surface;  // the part's colour, and 1 if it wears its texture

uniform sampler2D texture_map;

out vec4 frag_color;

void main() {
    vec3 texel = texture(texture_map, surface_uv).rgb;
    vec3 albedo = surface.a > 0.5 ? surface.rgb * texel : surface.rgb;
    frag_color = vec4(lit(albedo, world_normal), 1.0);
}
