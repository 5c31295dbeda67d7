#version 330
// The mirror quad: positions in world space, texture coordinates into the capture.
layout(location = 0) in vec3 position;
layout(location = 2) in vec2 uv;

uniform mat4 view_projection;

out vec2 environment_uv;

void main() {
    environment_uv = uv;
    gl_Position = view_projection * vec4(position, 1.0);
}
