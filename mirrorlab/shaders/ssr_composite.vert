#version 330
// A rectangle of the target (in normalised device coordinates) over a reflector drawn
// by screen-space reflections, for ssr_composite.frag.
layout(location = 0) in vec3 position;  // a unit square: x and y in [0, 1]

uniform vec4 rect;  // x0, y0, x1, y1 in normalised device coordinates

void main() {
    gl_ClipDistance[0] = 1.0;  // no clip plane cuts it (see clip.glsl)
    gl_Position = vec4(mix(rect.xy, rect.zw, position.xy), 0.0, 1.0);
}
