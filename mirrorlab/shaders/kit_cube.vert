#version 330 core
// The cube-map lab's sphere: world-space position and normal (a unit sphere moved to
// `center`).
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;

uniform mat4 view_projection;
uniform vec3 center;

out vec3 world_position;
out vec3 world_normal;

void main() {
    world_position = position + center;
    world_normal = normal;
    gl_Position = view_projection * vec4(world_position, 1.0);
}
