"""The quad lab's solution (teachers' only)."""

from OpenGL.GL import *  # noqa: F403

from mirrorlab.labs import kit

lab = kit.quad()

# --- variant: the numbers of the student's variant
COLOUR = (0.3, 0.2, 0.4)
# --- end of variant


def clear_background():
    glClearColor(*COLOUR, 1.0)
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)


def draw_quad():
    glDisable(GL_DEPTH_TEST)
    glColor3f(1.0, 1.0, 1.0)
    glBegin(GL_QUADS)
    for x, y in ((-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)):
        glVertex2f(x, y)
    glEnd()


def display():
    clear_background()
    draw_quad()
