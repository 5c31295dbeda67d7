#version 330
// The mirror quad: positions in world space. Its environment coordinate is either the
// quad's own texture coordinate (the lab's fixed capture) or the world position seen
// through a capture camera (projective, divided per fragment).
layout(location = 0) in vec3 position;
layout(location = 2) in vec2 uv;

uniform mat4 view_projection;
uniform bool projective;
uniform mat4 texture_matrix;

out vec4 environment_coord;

void main() {
    if (projective) {
        environment_coord = texture_matrix * vec4(position, 1.0);
    } else {
        environment_coord = vec4(uv, 0.0, 1.0);
    }
    gl_Position = view_projection * vec4(position, 1.0);
}
