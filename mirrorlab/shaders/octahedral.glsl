// The octahedral map (Engelhardt & Dachsbacher 2008; Cigolle et al. 2014), pulled in with
// #include "octahedral.glsl" (after common.glsl): mirrorlab.envmap.octahedral_map in GLSL,
// and the lookup of a texture whose mip levels each carry a one-texel border holding
// what lies across the square's edges (mirrorlab.envmap.octahedral_texel_grid). Level
// k's interior is n_k - 2 texels wide, so a point sits at another place in each level:
// the lookup picks the level from the footprint and filters between two levels itself.
uniform sampler2D octahedral_texture;
uniform int octahedral_levels;  // levels filled: 0 .. octahedral_levels - 1

// (u, v) in [-1, 1]^2 of a non-zero p = r / (|x| + |y| + |z|), folded with the signs
// `signs` (those of p's own x and y, or of a neighbour's: a branch that stays
// continuous across the lower half's edges, for a footprint's differences)
vec2 octahedral_uv(vec3 r, vec2 signs) {
    float l1 = abs(r.x) + abs(r.y) + abs(r.z);
    vec3 p = l1 > 0.0 ? r / l1 : vec3(0.0);
    return p.z < 0.0 ? (1.0 - abs(p.yx)) * signs : p.xy;
}

vec2 octahedral_signs(vec3 r) {
    return vec2(r.x >= 0.0 ? 1.0 : -1.0, r.y >= 0.0 ? 1.0 : -1.0);  // -0.0 counts as +
}

// mirrorlab.envmap.octahedral_map: finite and in [0, 1] for every input
vec2 octahedral_st(vec3 r) {
    return clamp(0.5 + 0.5 * octahedral_uv(r, octahedral_signs(r)), 0.0, 1.0);
}

vec3 octahedral_level(vec2 st, int level) {
    float size = float(textureSize(octahedral_texture, level).x);
    return textureLod(octahedral_texture, (1.0 + st * (size - 2.0)) / size, float(level)).rgb;
}

// The map's colour over a pixel whose lookup direction changes by dx, dy to its
// neighbours: the level from the footprint in texels of level 0 (as GL chooses it),
// linear between the two nearest levels.
vec3 map_color(vec3 look, vec3 dx, vec3 dy) {
    vec2 signs = octahedral_signs(look);
    vec2 uv = octahedral_uv(look, signs);
    vec2 step_x = 0.5 * (octahedral_uv(look + dx, signs) - uv);
    vec2 step_y = 0.5 * (octahedral_uv(look + dy, signs) - uv);
    float interior = float(textureSize(octahedral_texture, 0).x) - 2.0;
    float footprint = max(length(step_x), length(step_y)) * interior;
    float lod = clamp(log2(max(footprint, 1e-8)), 0.0, float(octahedral_levels - 1));
    int low = int(floor(lod));
    int high = min(low + 1, octahedral_levels - 1);
    vec2 st = clamp(0.5 + 0.5 * uv, 0.0, 1.0);
    return mix(octahedral_level(st, low), octahedral_level(st, high), lod - float(low));
}

// The lookup coordinates, for checks: (s, t, 0).
vec3 map_coordinates(vec3 look) {
    return vec3(octahedral_st(look), 0.0);
}
