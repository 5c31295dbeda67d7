#version 330
// Geometry in one flat colour (mirror backings and stencil masks), placed by model.
#include "clip.glsl"
#include "project.glsl"
layout(location = 0) in vec3 position;

uniform mat4 model;
uniform mat4 view_projection;

void main() {
    vec4 world_position = model * vec4(position, 1.0);
    clip_world(world_position);
    gl_Position = project(view_projection, world_position);
}
