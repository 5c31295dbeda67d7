#version 330
// "Demo style" (gamedev article): the texture indexed by the eye-space normal's x and y,
// u = nx w/2 + w/2 - 1 (a texel position, clamped to the map), v likewise; the texel
// position p becomes the texture coordinate (p + 0.5) / size. For a viewer infinitely
// far down -z this is exactly the sphere map; up close it ignores where the eye is.
in vec3 eye_normal;

uniform sampler2D normal_map_texture;
uniform vec2 map_size;  // texels (width, height)
uniform int output_mode;  // 0: colour; 1: the lookup coordinates (s, t, 0)

out vec4 frag_color;

void main() {
    float len = length(eye_normal);
    vec3 n = len > 1e-30 ? eye_normal / len : vec3(0.0);
    vec2 texel = clamp(n.xy * (map_size / 2.0) + (map_size / 2.0 - 1.0), vec2(0.0),
                       map_size - 1.0);
    vec2 st = (texel + 0.5) / map_size;
    if (output_mode == 1) {
        frag_color = vec4(st, 0.0, 1.0);
    } else {
        frag_color = vec4(texture(normal_map_texture, st).rgb, 1.0);
    }
}
