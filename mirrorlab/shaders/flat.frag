#version 330
uniform vec3 color;
uniform bool far_depth;  // write the far plane's depth, to reopen a region for drawing

out vec4 frag_color;

void main() {
    frag_color = vec4(color, 1.0);
    gl_FragDepth = far_depth ? 1.0 : gl_FragCoord.z;
}
