#version 330 compatibility
// The labs' given drawing: a part under the fixed-function matrices (glOrtho, gluLookAt,
// glPushMatrix ... that the student's code sets), lit in eye space.
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec2 uv;

out vec3 eye_normal;
out vec2 surface_uv;

void main() {
    eye_normal = gl_NormalMatrix * normal;
    surface_uv = uv;
    gl_Position = gl_ModelViewProjectionMatrix * vec4(position, 1.0);
}
