#version 330
// One side of a dual-paraboloid map resampled from a cube map (a live capture's six
// faces, as GTA V converts its probe every frame), drawn over the side's half of level 0
// by a triangle covering it (envmap_sky.vert): each texel shows the cube in the direction
// of its centre, continued past the rim in the margin
// (mirrorlab.envmap.paraboloid_map_inverse), filtered over the texel's area.
#include "common.glsl"

uniform samplerCube cube_map_texture;
uniform float side_size;  // texels a side of the half drawn
uniform int side;         // 0: the front (the left half), 1: the back
const float PARABOLOID_EXTENT = 1.0625;  // mirrorlab.envmap.PARABOLOID_EXTENT

out vec4 frag_color;

// the world direction at (s, t) of this side, continued past the rim
// (mirrorlab.envmap.paraboloid_map_inverse)
vec3 paraboloid_direction(vec2 st) {
    vec2 ab = (2.0 * st - 1.0) * PARABOLOID_EXTENT;
    float q = dot(ab, ab);
    vec3 e = vec3(2.0 * ab, q - 1.0) / (1.0 + q);
    return side == 0 ? vec3(-e.x, e.y, -e.z) : e;
}

void main() {
    vec2 st = (gl_FragCoord.xy - vec2(float(side) * side_size, 0.0)) / side_size;
    vec3 d = paraboloid_direction(st);
    // half the way to the neighbouring texels: the cube's level whose texels are half
    // the texel's size, read bilinearly, averages about the texel's own area
    vec3 dx = paraboloid_direction(st + vec2(0.5 / side_size, 0.0)) - d;
    vec3 dy = paraboloid_direction(st + vec2(0.0, 0.5 / side_size)) - d;
    frag_color = vec4(textureGrad(cube_map_texture, d, dx, dy).rgb, 1.0);
}
