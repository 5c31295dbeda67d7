#version 330
// The environment-mapped object: world- and eye-space position and normal for the
// per-fragment methods, and the per-vertex sphere-map coordinates for the per-vertex
// methods: mirrorlab's own sphere_map of the reflected view ray, or with texgen set, the
// formula of fixed-function GL_SPHERE_MAP texgen (texgen.glsl) as the textbook's
// sphere-texgen technique has it. The view matrix must be rigid, so that
// its upper 3x3 also carries normals from world to eye space. "World" positions are
// relative to the view's origin (camera-relative rendering): model and view are
// composed with that move in float64 on the CPU.
#include "common.glsl"
#include "clip.glsl"
#include "project.glsl"
#include "texgen.glsl"
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;

uniform mat4 model;
uniform mat4 view;
uniform mat4 projection;
uniform mat3 normal_matrix;  // inverse transpose of the model's upper 3x3
uniform bool orthographic;   // an orthographic view looks along eye -z everywhere
uniform bool texgen;         // per-vertex coordinates by GL_SPHERE_MAP texgen's formula

out vec3 world_position;
out vec3 world_normal;
out vec3 eye_position;
out vec3 eye_normal;
out vec2 vertex_sphere_st;

void main() {
    vec4 world = model * vec4(position, 1.0);
    vec4 eye = view * world;
    world_position = world.xyz;
    world_normal = normal_matrix * normal;
    eye_position = eye.xyz;
    eye_normal = mat3(view) * world_normal;
    if (texgen) {
        // texgen's view ray runs from the eye to the vertex; an orthographic view has no
        // eye point, and looks along -z from every vertex
        vertex_sphere_st = texgen_sphere_map(orthographic ? vec3(0.0, 0.0, -1.0) : eye.xyz,
                                             eye_normal);
    } else {
        // a vertex at the eye: r = 0
        vec3 u = orthographic ? vec3(0.0, 0.0, -1.0) : safe_normalize(eye.xyz, vec3(0.0));
        vec3 n = safe_normalize(eye_normal, vec3(0.0));       // no normal: r = u
        vertex_sphere_st = sphere_map(u - 2.0 * dot(n, u) * n);
    }
    clip_world(world);
    gl_Position = project(projection, eye);
}
