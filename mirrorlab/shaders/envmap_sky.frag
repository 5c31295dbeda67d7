#version 330
in vec2 ndc;

uniform samplerCube sky_texture;
uniform mat4 inverse_rotation_projection;  // inverse of projection @ (view's rotation)

out vec4 frag_color;

void main() {
    vec4 far_point = inverse_rotation_projection * vec4(ndc, 1.0, 1.0);
    vec3 direction = far_point.xyz / far_point.w;
    float len = length(direction);
    direction = len > 1e-30 ? direction / len : vec3(0.0, 0.0, -1.0);
    frag_color = vec4(texture(sky_texture, direction).rgb, 1.0);
}
