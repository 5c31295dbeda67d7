"""Sphere mapping: the textbook's cone, sphere-mapped with the launch picture twice, side
by side. On the {{shader_side}}: the kit's shader calling your GLSL functions, per
fragment. On the {{texgen_side}}: fixed-function GL_SPHERE_MAP texgen, per vertex.
Fill in the TODOs; README.md says how. Your variant: {{variant_line}}.

Check your work:  mirrorlab lab check spheremap starter.py
See it:           mirrorlab lab run spheremap starter.py
"""

from OpenGL.GL import *  # noqa: F403

from mirrorlab.labs import kit

lab = kit.spheremap()  # the context, the cone, the backdrop and the viewer
WIDTH, HEIGHT = lab.width, lab.height
launch = 0  # the launch picture's texture

SPHERE_MAP_GLSL = """
// TODO 1: the reflection of the view direction u about the unit normal n (eye space;
//         u runs from the eye to the point, both are unit length).
vec3 reflect_eye(vec3 u, vec3 n) {
    return vec3(0.0, 0.0, 1.0);
}

// TODO 2: the sphere map's (s, t) of the eye-space reflection vector r (Hoff).
vec2 sphere_map_st(vec3 r) {
    return vec2(0.5, 0.5);
}
"""


def load_textures():
    """The launch picture, on texture unit 0 (given)."""
    global launch
    launch = int(glGenTextures(1))
    lab.load_picture_texture(launch, "launch")


def setup_texgen():
    """TODO 3: make texgen compute s and t by the sphere-map formula, for texture unit
    {{unit}} (texgen's modes belong to the active unit: glActiveTexture({{unit_name}}))."""
    pass


def draw_cone_texgen():
    """TODO 4: the cone in the fixed-function pipeline (lab.draw_cone_fixed_function()),
    the launch picture bound on unit {{unit}}, texgen for s and t on (for that unit) while
    it is drawn and off again afterwards."""
    pass


def display():
    """One frame: the backdrop and a cone in each half of the window."""
    glClearColor(0.0, 0.0, 0.0, 1.0)
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)
    half = WIDTH // 2
    glViewport(0, 0, half, HEIGHT)
    lab.set_viewer(half / HEIGHT)
    lab.draw_backdrop()
    # TODO 5: {{left_cone}}

    glViewport(half, 0, WIDTH - half, HEIGHT)
    lab.set_viewer((WIDTH - half) / HEIGHT)
    lab.draw_backdrop()
    # TODO 5: {{right_cone}}

    glViewport(0, 0, WIDTH, HEIGHT)
