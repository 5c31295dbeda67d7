#version 330 core
// The labs' given drawing: a part under the fixed-function matrices (glOrtho, gluLookAt,
// glPushMatrix ... that the student's code sets; the trusted side sets them before each
// draw, from the context's stacks or the emulated ones), lit in eye space.
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec2 uv;

uniform mat4 ml_ModelViewProjectionMatrix;
uniform mat3 ml_NormalMatrix;

out vec3 eye_normal;
out vec2 surface_uv;

void main() {
    eye_normal = ml_NormalMatrix * normal;
    surface_uv = uv;
    gl_Position = ml_ModelViewProjectionMatrix * vec4(position, 1.0);
}
