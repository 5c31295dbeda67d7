"""Cube mapping: a chrome sphere whose cube map is captured live, six 90-degree pictures
from its centre each frame, and looked up through your own face selection in the shader.
Fill in the TODOs; README.md beside this file says how.
Your variant: {{variant_line}}.

Check your work:  mirrorlab lab check cubemap starter.py
See it:           mirrorlab lab run cubemap starter.py
"""

from OpenGL.GL import *  # noqa: F403
from OpenGL.GLU import gluLookAt, gluPerspective  # noqa: F401

from mirrorlab.labs import kit

lab = kit.cubemap()  # the context, the objects, the sphere and the viewer
WIDTH, HEIGHT = lab.width, lab.height
FACE_SIZE = 128  # texels on a side of each face
cube_texture = 0

CUBE_MAP_GLSL = """
// TODO 1: the face the direction r hits: 0..5 for +X, -X, +Y, -Y, +Z, -Z.
int cube_face(vec3 r) {
    return 0;
}

// TODO 2: (s, t) in [0, 1] on that face, by the OpenGL table.
vec2 cube_face_st(vec3 r, int face) {
    return vec2(0.5, 0.5);
}
"""

# TODO 3: where each face's camera looks, and its up, in the order of the faces
#         (GL_TEXTURE_CUBE_MAP_POSITIVE_X, NEGATIVE_X, POSITIVE_Y, ...):
#         ((dx, dy, dz), (ux, uy, uz)) for each face
FACE_VIEWS: list = []


def create_cube_texture():
    """The cube map: six blank FACE_SIZE faces on texture unit 1 (given)."""
    global cube_texture
    cube_texture = int(glGenTextures(1))
    glActiveTexture(GL_TEXTURE1)
    glBindTexture(GL_TEXTURE_CUBE_MAP, cube_texture)
    for face in range(6):
        glTexImage2D(
            GL_TEXTURE_CUBE_MAP_POSITIVE_X + face,
            0,
            GL_RGB,
            FACE_SIZE,
            FACE_SIZE,
            0,
            GL_RGB,
            GL_UNSIGNED_BYTE,
            None,
        )
    glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MIN_FILTER, GL_LINEAR)
    glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MAG_FILTER, GL_LINEAR)
    for wrap in (GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R):
        glTexParameteri(GL_TEXTURE_CUBE_MAP, wrap, GL_CLAMP_TO_EDGE)
    glActiveTexture(GL_TEXTURE0)


def capture_cube():
    """Six pictures of the scene from the sphere's centre, {{center}}, one per face."""
    glViewport(0, 0, FACE_SIZE, FACE_SIZE)
    # TODO 3: a square 90-degree projection; for each face, clear, place the camera at the
    #         centre looking along the face's direction with its up, draw lab.draw_scene()
    # TODO 4: ... and copy the picture into that face of cube_texture (bound on unit 1)

    glViewport(0, 0, WIDTH, HEIGHT)


def display():
    """One frame: the live capture, then the scene and the sphere from the viewer."""
    glClearColor(*lab.BACKGROUND, 1.0)
    # TODO 5: the capture goes first

    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)
    lab.set_viewer()
    lab.draw_scene()
    lab.draw_sphere(CUBE_MAP_GLSL, cube_texture)
