#version 330
// One mip level of an octahedral map resampled from a cube map (a live capture's six
// faces), drawn over the level by a triangle covering it (envmap_sky.vert): each texel,
// its border too, shows the cube in the direction of its centre
// (mirrorlab.envmap.octahedral_texel_grid), filtered over the texel's footprint (the
// directions of the texels beside it, across the square's edges as the border continues
// them), so a coarse level is made from the cube's matching coarse level.
#include "common.glsl"

uniform samplerCube cube_map_texture;
uniform float level_size;  // texels a side of the level drawn

out vec4 frag_color;

// the unit direction at octahedral (s, t), continued past the square's edges
// (mirrorlab.envmap.octahedral_map_inverse)
vec3 octahedral_direction(vec2 st) {
    vec2 uv = mod(2.0 * st - 1.0 + 2.0, 4.0) - 2.0;
    if (abs(uv.x) > 1.0) {
        uv = vec2(sign(uv.x) * 2.0 - uv.x, -uv.y);
    }
    if (abs(uv.y) > 1.0) {
        uv = vec2(-uv.x, sign(uv.y) * 2.0 - uv.y);
    }
    float z = 1.0 - abs(uv.x) - abs(uv.y);
    vec2 xy = z < 0.0 ? (1.0 - abs(uv.yx)) * vec2(uv.x >= 0.0 ? 1.0 : -1.0,
                                                  uv.y >= 0.0 ? 1.0 : -1.0)
                      : uv;
    return safe_normalize(vec3(xy, z), vec3(0.0, 0.0, 1.0));
}

void main() {
    float interior = level_size - 2.0;
    vec2 st = (gl_FragCoord.xy - 1.0) / interior;  // texel i's centre: (i - 0.5) / interior
    vec3 d = octahedral_direction(st);
    // half the way to the neighbouring texels: the cube's level whose texels are half
    // the texel's size, read bilinearly, averages about the texel's own area (as
    // mirrorlab.envmap.octahedral_levels filters a level from the one below it)
    vec3 dx = octahedral_direction(st + vec2(0.5 / interior, 0.0)) - d;
    vec3 dy = octahedral_direction(st + vec2(0.0, 0.5 / interior)) - d;
    frag_color = vec4(textureGrad(cube_map_texture, d, dx, dy).rgb, 1.0);
}
