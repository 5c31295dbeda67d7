#version 330
// Scene parts, one draw call each: world-space normal and texture coordinate to the
// fragment stage. model places a part relative to the view's origin (camera-relative
// rendering: composed in float64 on the CPU), and view_projection takes such positions.
// view_projection may show the world seen in a mirror; the normal and the clip distance
// stay in the unreflected world, so shading matches the real part and the clip plane
// cuts away what lies behind the mirror. (scene_packed.vert draws every part of a pass
// in one multi-draw, reading the same two matrices from a buffer.)
#include "clip.glsl"
#include "project.glsl"
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec2 uv;

uniform mat4 model;
uniform mat4 view_projection;
uniform mat4 part;  // upper-left 3x3: the normal matrix; column 3: colour, and 1 if textured

out vec3 world_normal;
out vec2 surface_uv;
flat out vec4 surface;  // the part's colour, and 1 if it wears its texture

void main() {
    vec4 world_position = model * vec4(position, 1.0);
    world_normal = mat3(part) * normal;
    surface_uv = uv;
    surface = part[3];
    clip_world(world_position);
    gl_Position = project(view_projection, world_position);
}
