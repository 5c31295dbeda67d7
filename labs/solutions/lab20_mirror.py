"""Lab 20: the multipass mirror, a reference solution (teachers only: see labs/README.md).

Pass 1 draws the scene from the mirror's point of view and copies the picture into the
ENVIRONMENT texture; pass 2 draws the scene from the viewer and the mirror quad wearing
that texture. The numbers of the variant are in the block below (``mirrorlab lab
solution`` writes a student's there).
"""

from OpenGL.GL import *  # noqa: F403
from OpenGL.GLU import gluLookAt

from mirrorlab.labs import kit

lab = kit.lab20()  # the context, the shaders, the robot and the viewer
WIDTH, HEIGHT = lab.width, lab.height

# --- variant: the mirror in the plane x = MIRROR_X, from Y0 to Y1 and Z0 to Z1
MIRROR_X = -7
Y0, Y1 = -3, 5
Z0, Z1 = -6, 2
# --- end of variant

ENVIRONMENT, METAL = 0, 1  # indices into tex_ids
tex_ids = [0, 0]
robot = None


def load_textures():
    """Make METAL (given) and the blank ENVIRONMENT texture."""
    global tex_ids
    tex_ids = [int(name) for name in glGenTextures(2)]
    lab.load_picture_texture(tex_ids[METAL], "metal")
    # ENVIRONMENT lives on texture unit 1; the scene's own textures use unit 0.
    glActiveTexture(GL_TEXTURE1)
    glBindTexture(GL_TEXTURE_2D, tex_ids[ENVIRONMENT])
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, WIDTH, HEIGHT, 0, GL_RGB, GL_UNSIGNED_BYTE, None)
    # TODO 4: filters and wrapping of ENVIRONMENT (no mipmaps)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE)
    glActiveTexture(GL_TEXTURE0)


def build_scene_graph():
    """The robot's scene graph (given), with the base wearing METAL."""
    global robot
    robot = lab.robot_graph()
    # TODO 5: the base's texture
    robot["base"].texture = tex_ids[METAL]


def create_mirror():
    """Pass 1: the world seen from the mirror, copied into ENVIRONMENT."""
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)
    # TODO 1: the capture's orthographic projection and camera
    glMatrixMode(GL_PROJECTION)
    glLoadIdentity()
    glOrtho(Z0, Z1, Y0, Y1, 0, 15)
    glMatrixMode(GL_MODELVIEW)
    glLoadIdentity()
    gluLookAt(MIRROR_X, 0, 0, 0, 0, 0, 0, 1, 0)
    # TODO 2: draw the scene, without the mirror
    lab.draw_scene(robot)
    # TODO 3: copy the framebuffer into ENVIRONMENT
    glActiveTexture(GL_TEXTURE1)
    glBindTexture(GL_TEXTURE_2D, tex_ids[ENVIRONMENT])
    glCopyTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, 0, 0, WIDTH, HEIGHT, 0)
    glActiveTexture(GL_TEXTURE0)


def render_mirror():
    """Pass 2's mirror: the quad in the plane x = MIRROR_X wearing ENVIRONMENT."""
    # TODO 6: texture shader, sampler uniform and ENVIRONMENT for the mirror
    glUseProgram(lab.textureShader)
    glUniform1i(lab.texSampler, 1)
    glActiveTexture(GL_TEXTURE1)
    glBindTexture(GL_TEXTURE_2D, tex_ids[ENVIRONMENT])
    glActiveTexture(GL_TEXTURE0)
    # TODO 7: the quad's corners and texture coordinates
    glBegin(GL_QUADS)
    glTexCoord2f(0, 0)
    glVertex3f(MIRROR_X, Y0, Z0)
    glTexCoord2f(0, 1)
    glVertex3f(MIRROR_X, Y1, Z0)
    glTexCoord2f(1, 1)
    glVertex3f(MIRROR_X, Y1, Z1)
    glTexCoord2f(1, 0)
    glVertex3f(MIRROR_X, Y0, Z1)
    glEnd()
    glUseProgram(0)


def display():
    """One frame: the capture, then the camera pass."""
    # TODO 8: pass 1
    create_mirror()
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)
    lab.set_viewer()
    lab.draw_scene(robot)
    # TODO 8: pass 2
    render_mirror()
