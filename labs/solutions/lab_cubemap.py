"""Cube mapping, a reference solution (teachers only: see labs/README.md): a chrome
sphere whose cube map is captured live, six 90-degree pictures from its centre each
frame, and looked up through the face selection in the shader. The numbers of the variant
are in the block below (``mirrorlab lab solution`` writes a student's there).
"""

from OpenGL.GL import *  # noqa: F403
from OpenGL.GLU import gluLookAt, gluPerspective

from mirrorlab.labs import kit

lab = kit.cubemap()  # the context, the objects, the sphere and the viewer
WIDTH, HEIGHT = lab.width, lab.height
FACE_SIZE = 128  # texels on a side of each face
cube_texture = 0

# --- variant: the sphere's centre, where the six cameras sit
CENTER = (0, 0, 0)
# --- end of variant

CUBE_MAP_GLSL = """
// Task 1: the face the direction r hits: 0..5 for +X, -X, +Y, -Y, +Z, -Z.
int cube_face(vec3 r) {
    vec3 a = abs(r);
    if (a.x >= a.y && a.x >= a.z) {
        return r.x >= 0.0 ? 0 : 1;
    }
    if (a.y >= a.z) {
        return r.y >= 0.0 ? 2 : 3;
    }
    return r.z >= 0.0 ? 4 : 5;
}

// Task 2: (s, t) in [0, 1] on that face, by the OpenGL table.
vec2 cube_face_st(vec3 r, int face) {
    float sc;
    float tc;
    float ma;
    if (face == 0) { sc = -r.z; tc = -r.y; ma = abs(r.x); }
    else if (face == 1) { sc = r.z; tc = -r.y; ma = abs(r.x); }
    else if (face == 2) { sc = r.x; tc = r.z; ma = abs(r.y); }
    else if (face == 3) { sc = r.x; tc = -r.z; ma = abs(r.y); }
    else if (face == 4) { sc = r.x; tc = -r.y; ma = abs(r.z); }
    else { sc = -r.x; tc = -r.y; ma = abs(r.z); }
    return vec2((sc / ma + 1.0) / 2.0, (tc / ma + 1.0) / 2.0);
}
"""

# Task 3: where each face's camera looks, and its up, in the order of the faces
FACE_VIEWS = [
    ((1, 0, 0), (0, -1, 0)),  # GL_TEXTURE_CUBE_MAP_POSITIVE_X
    ((-1, 0, 0), (0, -1, 0)),  # NEGATIVE_X
    ((0, 1, 0), (0, 0, 1)),  # POSITIVE_Y
    ((0, -1, 0), (0, 0, -1)),  # NEGATIVE_Y
    ((0, 0, 1), (0, -1, 0)),  # POSITIVE_Z
    ((0, 0, -1), (0, -1, 0)),  # NEGATIVE_Z
]


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
    """Tasks 3 and 4: six pictures of the scene from the sphere's centre, one per face."""
    cx, cy, cz = CENTER
    glViewport(0, 0, FACE_SIZE, FACE_SIZE)
    glMatrixMode(GL_PROJECTION)
    glLoadIdentity()
    gluPerspective(90, 1, 0.05, 50)
    for face, ((dx, dy, dz), (ux, uy, uz)) in enumerate(FACE_VIEWS):
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)
        glMatrixMode(GL_MODELVIEW)
        glLoadIdentity()
        gluLookAt(cx, cy, cz, cx + dx, cy + dy, cz + dz, ux, uy, uz)
        lab.draw_scene()
        glActiveTexture(GL_TEXTURE1)
        glBindTexture(GL_TEXTURE_CUBE_MAP, cube_texture)
        glCopyTexImage2D(
            GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0, GL_RGB, 0, 0, FACE_SIZE, FACE_SIZE, 0
        )
        glActiveTexture(GL_TEXTURE0)
    glViewport(0, 0, WIDTH, HEIGHT)


def display():
    """One frame: the live capture, then the scene and the sphere from the viewer."""
    glClearColor(*lab.BACKGROUND, 1.0)
    # Task 5: the capture first
    capture_cube()
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)
    lab.set_viewer()
    lab.draw_scene()
    lab.draw_sphere(CUBE_MAP_GLSL, cube_texture)
