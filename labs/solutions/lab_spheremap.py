"""Sphere mapping, a reference solution (teachers only: see labs/README.md): the
textbook's cone, sphere-mapped with the launch picture twice, side by side: the kit's
shader calling the GLSL functions, per fragment, and fixed-function GL_SPHERE_MAP texgen,
per vertex. The numbers of the variant are in the block below (``mirrorlab lab
solution`` writes a student's there).
"""

from OpenGL.GL import *  # noqa: F403

from mirrorlab.labs import kit

lab = kit.spheremap()  # the context, the cone, the backdrop and the viewer
WIDTH, HEIGHT = lab.width, lab.height
launch = 0  # the launch picture's texture

# --- variant: the side of the shader's cone and texgen's texture unit
SHADER_SIDE = "left"
UNIT = 0
# --- end of variant

SPHERE_MAP_GLSL = """
// Task 1: the reflection of the view direction u about the unit normal n (eye space).
vec3 reflect_eye(vec3 u, vec3 n) {
    return u - 2.0 * dot(n, u) * n;
}

// Task 2: the sphere map's (s, t) of the eye-space reflection vector r.
vec2 sphere_map_st(vec3 r) {
    float m = 2.0 * sqrt(r.x * r.x + r.y * r.y + (r.z + 1.0) * (r.z + 1.0));
    return vec2(r.x / m + 0.5, r.y / m + 0.5);
}
"""


def load_textures():
    """The launch picture, on texture unit 0 (given)."""
    global launch
    launch = int(glGenTextures(1))
    lab.load_picture_texture(launch, "launch")


def setup_texgen():
    """Task 3: texgen makes s and t by the sphere-map formula, for the variant's unit."""
    glActiveTexture(GL_TEXTURE0 + UNIT)
    glTexGeni(GL_S, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)
    glTexGeni(GL_T, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)
    glActiveTexture(GL_TEXTURE0)


def draw_cone_texgen():
    """Task 4: the cone in the fixed-function pipeline, texgen on for it alone."""
    glActiveTexture(GL_TEXTURE0 + UNIT)
    glBindTexture(GL_TEXTURE_2D, launch)
    glEnable(GL_TEXTURE_GEN_S)
    glEnable(GL_TEXTURE_GEN_T)
    lab.draw_cone_fixed_function()
    glDisable(GL_TEXTURE_GEN_S)
    glDisable(GL_TEXTURE_GEN_T)
    glActiveTexture(GL_TEXTURE0)


def display():
    """One frame: the backdrop and a cone in each half of the window."""
    glClearColor(0.0, 0.0, 0.0, 1.0)
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)
    half = WIDTH // 2
    # Task 5: the shader's cone on the variant's side, the texgen cone on the other
    glViewport(0, 0, half, HEIGHT)
    lab.set_viewer(half / HEIGHT)
    lab.draw_backdrop()
    if SHADER_SIDE == "left":
        lab.draw_cone_shader(SPHERE_MAP_GLSL, launch)
    else:
        draw_cone_texgen()
    glViewport(half, 0, WIDTH - half, HEIGHT)
    lab.set_viewer((WIDTH - half) / HEIGHT)
    lab.draw_backdrop()
    if SHADER_SIDE == "left":
        draw_cone_texgen()
    else:
        lab.draw_cone_shader(SPHERE_MAP_GLSL, launch)
    glViewport(0, 0, WIDTH, HEIGHT)
