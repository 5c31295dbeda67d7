#version 330
// A 2D texture on a screen rectangle, with its alpha (text over the frame) or opaque.
in vec2 quad_uv;

uniform sampler2D picture;
uniform bool opaque;

out vec4 color;

void main() {
    vec4 texel = texture(picture, quad_uv);
    color = opaque ? vec4(texel.rgb, 1.0) : texel;
}
