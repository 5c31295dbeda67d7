#version 330
// The distant environment behind everything: one triangle covering the screen, at the
// far plane; each fragment looks up its own view direction.
layout(location = 0) in vec3 position;  // NDC x, y (z unused)

out vec2 ndc;

void main() {
    ndc = position.xy;
    gl_ClipDistance[0] = 1.0;  // never clipped (see clip.glsl: every vertex shader writes it)
    gl_Position = vec4(position.xy, 1.0, 1.0);
}
