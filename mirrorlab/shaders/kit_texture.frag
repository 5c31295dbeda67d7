#version 330 core
// Unlit: the texture's colour as it is (a captured image is already lit).
in vec2 texture_coordinate;

uniform sampler2D texSampler;

out vec4 frag_color;

void main() {
    frag_color = vec4(texture(texSampler, texture_coordinate).rgb, 1.0);
}
