"""Lab 20: the multipass mirror. Fill in the TODOs; README.md beside this file says how.
Your variant: {{variant_line}}.

Pass 1 (create_mirror) draws the scene from the mirror's point of view and copies the
picture into the ENVIRONMENT texture; pass 2 (display, then render_mirror) draws the scene
from the viewer and the mirror quad wearing that texture.

Check your work:  mirrorlab lab check lab20 starter.py
See it:           mirrorlab lab run lab20 starter.py
"""

from OpenGL.GL import *  # noqa: F403
from OpenGL.GLU import gluLookAt  # noqa: F401

from mirrorlab.labs import kit

lab = kit.lab20()  # the context, the shaders, the robot and the viewer
WIDTH, HEIGHT = lab.width, lab.height

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
    # TODO 4: ENVIRONMENT's filters (both GL_LINEAR) and wrapping (both clamped); no mipmaps

    glActiveTexture(GL_TEXTURE0)


def build_scene_graph():
    """The robot's scene graph (given), with the base wearing METAL."""
    global robot
    robot = lab.robot_graph()
    # TODO 5: give the base (robot["base"]) the METAL texture


def create_mirror():
    """Pass 1: the world seen from the mirror, copied into ENVIRONMENT."""
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)
    # TODO 1: the orthographic projection whose box is your mirror (its corners:
    #         {{corners}}), near 0 and far 15, and the camera at {{eye}}
    #         looking at the origin, up (0, 1, 0) (README.md, task 1, says why)

    # TODO 2: draw the scene (lab.draw_scene(robot)), without the mirror

    # TODO 3: copy the framebuffer into ENVIRONMENT (bound on unit 1), level 0, WIDTH x HEIGHT

    pass


def render_mirror():
    """Pass 2's mirror: the quad in the plane x = {{x}} wearing ENVIRONMENT."""
    # TODO 6: use lab.textureShader, point its sampler (lab.texSampler) at unit 1 and bind
    #         ENVIRONMENT there

    # TODO 7: the quad {{corners}} with texture coordinates
    #         that match the capture (glBegin(GL_QUADS), glTexCoord2f, glVertex3f, glEnd)

    pass


def display():
    """One frame: the capture, then the camera pass."""
    # TODO 8: pass 1 goes here

    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)
    lab.set_viewer()
    lab.draw_scene(robot)
    # TODO 8: and the mirror here
