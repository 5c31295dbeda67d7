#version 330
// Scene parts: world-space normal and texture coordinate to the fragment stage.
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec2 uv;

uniform mat4 model;
uniform mat4 view_projection;
uniform mat3 normal_matrix;

out vec3 world_normal;
out vec2 surface_uv;

void main() {
    world_normal = normal_matrix * normal;
    surface_uv = uv;
    gl_Position = view_projection * model * vec4(position, 1.0);
}
