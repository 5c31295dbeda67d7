#version 430
// Scene parts, every part of a pass in one glMultiDrawElementsIndirect: each command
// draws consecutive parts of one mesh as its instances, its base instance the first one's
// place in the parts buffer, so part gl_BaseInstance + gl_InstanceID is drawn, with the
// same model and part matrices scene.vert takes as uniforms: the same picture, pixel for
// pixel.
#extension GL_ARB_shader_draw_parameters : require
#include "clip.glsl"
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec2 uv;

struct Part {
    mat4 model;  // mesh to origin-relative world
    mat4 part;   // upper-left 3x3: the normal matrix; column 3: colour, and 1 if textured
};
layout(std430, binding = 0) readonly buffer Parts {
    Part parts[];
};

uniform mat4 view_projection;

out vec3 world_normal;
out vec2 surface_uv;
flat out vec4 surface;

void main() {
    Part drawn = parts[gl_BaseInstanceARB + gl_InstanceID];
    vec4 world_position = drawn.model * vec4(position, 1.0);
    world_normal = mat3(drawn.part) * normal;
    surface_uv = uv;
    surface = drawn.part[3];
    clip_world(world_position);
    gl_Position = view_projection * world_position;
}
