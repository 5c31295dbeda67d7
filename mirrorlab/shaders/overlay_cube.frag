#version 330
// One face of a cube map on a screen rectangle, upright as a skybox picture is: the
// face's t = 0 edge at the top (the cube-map table's sc, tc per face, GL order +X..-Z).
in vec2 quad_uv;

uniform samplerCube cube;
uniform int face;

out vec4 color;

void main() {
    float sc = 2.0 * quad_uv.x - 1.0;
    float tc = 1.0 - 2.0 * quad_uv.y;
    vec3 direction;
    if (face == 0) direction = vec3(1.0, -tc, -sc);
    else if (face == 1) direction = vec3(-1.0, -tc, sc);
    else if (face == 2) direction = vec3(sc, 1.0, tc);
    else if (face == 3) direction = vec3(sc, -1.0, -tc);
    else if (face == 4) direction = vec3(sc, -tc, 1.0);
    else direction = vec3(-sc, -tc, -1.0);
    color = vec4(texture(cube, direction).rgb, 1.0);
}
