#version 330 core
// The sphere-map lab's cone: eye-space position and normal for the fragment stage.
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;

uniform mat4 ml_ModelViewMatrix;           // set by the trusted side before each draw
uniform mat4 ml_ModelViewProjectionMatrix;
uniform mat3 ml_NormalMatrix;

out vec3 eye_position;
out vec3 eye_normal;

void main() {
    eye_position = (ml_ModelViewMatrix * vec4(position, 1.0)).xyz;
    eye_normal = ml_NormalMatrix * normal;
    gl_Position = ml_ModelViewProjectionMatrix * vec4(position, 1.0);
}
