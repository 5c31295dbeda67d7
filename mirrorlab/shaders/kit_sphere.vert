#version 330 compatibility
// The sphere-map lab's cone: eye-space position and normal for the fragment stage.
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;

out vec3 eye_position;
out vec3 eye_normal;

void main() {
    eye_position = (gl_ModelViewMatrix * vec4(position, 1.0)).xyz;
    eye_normal = gl_NormalMatrix * normal;
    gl_Position = gl_ModelViewProjectionMatrix * vec4(position, 1.0);
}
