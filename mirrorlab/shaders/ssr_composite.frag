#version 330
// Screen-space reflections, last step: where the march covered a pixel of the reflector,
// its colour becomes the hit's, mixed by the hit's weight with the probe's (what the
// frame copy holds there), and alpha goes back to 1.
uniform sampler2D hit_colors;
uniform sampler2D hit_infos;
uniform sampler2D frame_color;

out vec4 frag_color;

void main() {
    ivec2 here = ivec2(gl_FragCoord.xy);
    vec4 info = texelFetch(hit_infos, here, 0);
    if (info.y < 0.5) {
        discard;  // not a pixel of the reflector
    }
    vec3 probe = texelFetch(frame_color, here, 0).rgb;
    vec3 hit = texelFetch(hit_colors, here, 0).rgb;
    frag_color = vec4(mix(probe, hit, clamp(info.x, 0.0, 1.0)), 1.0);
}
