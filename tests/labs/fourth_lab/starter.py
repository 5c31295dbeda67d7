"""The quad lab. Your variant: {{variant_line}}.

Check your work:  mirrorlab lab check quad starter.py
"""

from OpenGL.GL import *  # noqa: F403

from mirrorlab.labs import kit

lab = kit.quad()


def clear_background():
    """TODO 1: clear the frame to {{colour}}."""


def draw_quad():
    """TODO 2: a white quad, corners (-0.5, -0.5) to (0.5, 0.5)."""


def display():
    clear_background()
    draw_quad()
