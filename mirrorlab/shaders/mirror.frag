#version 330
// Unlit: the captured image is already lit. The back of the mirror shows its backing.
in vec4 environment_coord;

uniform sampler2D environment;
uniform vec3 backing_color;

out vec4 frag_color;

void main() {
    if (gl_FrontFacing) {
        frag_color = vec4(textureProj(environment, environment_coord.xyw).rgb, 1.0);
    } else {
        frag_color = vec4(backing_color, 1.0);
    }
}
