#version 330
// A rectangle on the screen (the demo's help text and insets): the unit quad's corner
// (0..1, 0..1) placed at rect = (left, bottom, right, top) in normalised device coordinates.
layout(location = 0) in vec3 position;
layout(location = 2) in vec2 uv;

uniform vec4 rect;

out vec2 quad_uv;

void main() {
    quad_uv = uv;
    gl_Position = vec4(mix(rect.xy, rect.zw, position.xy), 0.0, 1.0);
}
