#version 330
// Scene parts, every part of a pass in one glMultiDrawElementsIndirect: each command
// draws consecutive parts of one mesh as its instances, its base instance the first one's
// place in the parts buffer. A part's two matrices are per-instance attributes (the
// vertex array's binding of the parts buffer, divisor 1), so instance i of a command
// with base instance b reads part b + i: the same model and part matrices scene.vert
// takes as uniforms, and the same picture, pixel for pixel. (llvmpipe's vertex work for
// a small part was about four times as slow reading them from a storage buffer indexed
// by the instance.)
#include "clip.glsl"
#include "project.glsl"
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec2 uv;
layout(location = 3) in mat4 model;  // mesh to origin-relative world (locations 3-6)
layout(location = 7) in mat4 part;   // upper-left 3x3: the normal matrix; column 3:
                                     // colour, and 1 if textured (locations 7-10)

uniform mat4 view_projection;

out vec3 world_normal;
out vec2 surface_uv;
flat out vec4 surface;

void main() {
    vec4 world_position = model * vec4(position, 1.0);
    world_normal = mat3(part) * normal;
    surface_uv = uv;
    surface = part[3];
    clip_world(world_position);
    gl_Position = project(view_projection, world_position);
}
