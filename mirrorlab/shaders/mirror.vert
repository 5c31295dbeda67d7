#version 330
// A planar mirror: positions relative to its centre, placed by model (world relative to
// the view's origin: camera-relative rendering). Its environment coordinate is either
// the quad's own texture coordinate (the lab's fixed orthographic capture) or the
// position seen through the capture's camera (projective, divided per fragment).
#include "clip.glsl"
#include "project.glsl"
layout(location = 0) in vec3 position;
layout(location = 2) in vec2 uv;

uniform mat4 model;
uniform mat4 view_projection;
uniform bool projective;
uniform mat4 texture_matrix;

out vec4 environment_coord;

void main() {
    vec4 world_position = model * vec4(position, 1.0);
    if (projective) {
        environment_coord = texture_matrix * world_position;
    } else {
        environment_coord = vec4(uv, 0.0, 1.0);
    }
    clip_world(world_position);
    gl_Position = project(view_projection, world_position);
}
