#version 330
// The distant environment: each fragment looks up the world direction of its view ray.
#include "common.glsl"
#include "warp.glsl"
in vec2 ndc;

uniform samplerCube sky_texture;
uniform mat3 ndc_to_direction;  // (ndc x, ndc y, 1) -> world direction of the view ray (a
                                // warped view's: its eye-to-world rotation, warp.glsl)

out vec4 frag_color;

void main() {
    vec3 direction = safe_normalize(view_direction(ndc_to_direction, ndc), vec3(0.0, 0.0, -1.0));
    frag_color = vec4(texture(sky_texture, direction).rgb, 1.0);
}
