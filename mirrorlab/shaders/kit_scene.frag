#version 330 core
// Lambert lighting from one directional light given in eye space, plus ambient.
in vec3 eye_normal;
in vec2 surface_uv;

uniform vec3 color;
uniform bool use_texture;
uniform sampler2D surface;
uniform vec3 light_eye;
uniform float ambient;
uniform float diffuse;

out vec4 frag_color;

void main() {
    vec3 albedo = color;
    if (use_texture) {
        albedo *= texture(surface, surface_uv).rgb;
    }
    float lambert = max(dot(normalize(eye_normal), light_eye), 0.0);
    frag_color = vec4(albedo * (ambient + diffuse * lambert), 1.0);
}
