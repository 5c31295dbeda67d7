"""The backends that need a display: the hidden glfw window chosen when libEGL.so.1
cannot be loaded (hidden with bubblewrap) and forced with MIRRORLAB_GL_BACKEND, its 4.1
core context, and a visible window asked for as core. Frames are compared with EGL's.
Each case is a fresh process: PyOpenGL binds a process once."""

from __future__ import annotations

import os

import numpy as np

from tests.gl.test_backends import (
    COMPATIBILITY_PROFILE_BIT,
    CORE_PROFILE_BIT,
    FORWARD_COMPATIBLE_BIT,
    PROBE,
    hide_egl,
    mirrorlab,
    png,
    python,
)

TWO_HIDDEN = """
from mirrorlab.gl.context import offscreen_context
from mirrorlab.gl.resources import Framebuffer
first = offscreen_context()
second = offscreen_context()
first.release()  # glfw stays up for the second window
second.make_current()
from OpenGL import GL
target = Framebuffer(second.resources, 8, 4)
target.bind()
GL.glClearColor(0.0, 1.0, 0.0, 1.0)
GL.glClear(GL.GL_COLOR_BUFFER_BIT)
pixel = GL.glReadPixels(0, 0, 1, 1, GL.GL_RGB, GL.GL_UNSIGNED_BYTE)
print(second.backend, list(bytes(pixel)))
target.release()
second.release()
"""

WINDOW = """
from mirrorlab.gl.context import window_context
with window_context(64, 48, "core window") as context:  # before OpenGL is imported
    from OpenGL import GL
    print(context.backend, context.core, int(GL.glGetIntegerv(GL.GL_CONTEXT_PROFILE_MASK)))
"""


def probe(prefix: tuple[str, ...] = (), **env: str) -> list[str]:
    done = python(PROBE, prefix, DISPLAY=_display(), **env)
    assert done.returncode == 0, done.stderr
    return done.stdout.split()


def _display() -> str:
    return os.environ["DISPLAY"]


def test_without_egl_render_writes_the_default_frame_in_a_hidden_window(tmp_path):
    egl = mirrorlab("render", "--out", str(tmp_path / "egl.png"), DISPLAY=_display())
    assert egl.returncode == 0, egl.stderr
    done = mirrorlab(
        "render", "--out", str(tmp_path / "hidden.png"), prefix=hide_egl(), DISPLAY=_display()
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith(f"wrote {tmp_path / 'hidden.png'} (512x512, lab20")
    hidden = png(tmp_path / "hidden.png")
    assert hidden.shape == (512, 512, 3)
    assert np.array_equal(hidden, png(tmp_path / "egl.png"))  # measured: pixel-identical
    # and the chooser said so
    assert probe(hide_egl())[:3] == ["hidden-window", "False", "glx"]


def test_a_display_does_not_take_egl_away_unless_forced():
    assert probe()[:3] == ["egl", "False", "egl"]
    backend, core, platform, mask, _, legacy = probe(MIRRORLAB_GL_BACKEND="hidden-window")
    assert (backend, core, platform) == ("hidden-window", "False", "glx")
    assert int(mask) & COMPATIBILITY_PROFILE_BIT and legacy == "matrix-mode"


def test_a_forced_hidden_window_renders_the_same_frames_as_egl(tmp_path):
    for name, backend in (("egl", "egl"), ("hidden", "hidden-window")):
        done = mirrorlab(
            "render",
            "mirror_and_sphere",
            "--size",
            "96x64",
            "--out",
            str(tmp_path / f"{name}.png"),
            DISPLAY=_display(),
            MIRRORLAB_GL_BACKEND=backend,
        )
        assert done.returncode == 0, done.stderr
    assert np.array_equal(png(tmp_path / "egl.png"), png(tmp_path / "hidden.png"))


def test_the_core_variable_gives_a_core_forward_compatible_hidden_window():
    backend, core, platform, mask, flags, legacy = probe(
        MIRRORLAB_GL_BACKEND="hidden-window", MIRRORLAB_GL_CORE="1"
    )
    assert (backend, core, platform) == ("hidden-window", "True", "glx")
    assert int(mask) & CORE_PROFILE_BIT and not int(mask) & COMPATIBILITY_PROFILE_BIT
    assert int(flags) & FORWARD_COMPATIBLE_BIT
    assert legacy == "no-matrix-mode"


def test_releasing_one_hidden_window_leaves_the_others_working():
    done = python(TWO_HIDDEN, DISPLAY=_display(), MIRRORLAB_GL_BACKEND="hidden-window")
    assert done.returncode == 0, done.stderr
    assert done.stdout.split("\n")[0] == "hidden-window [0, 255, 0]"


def test_a_visible_window_asked_for_as_core_is_core():
    for core, expected in (("0", COMPATIBILITY_PROFILE_BIT), ("1", CORE_PROFILE_BIT)):
        done = python(WINDOW, DISPLAY=_display(), MIRRORLAB_GL_CORE=core)
        assert done.returncode == 0, done.stderr
        backend, asked, mask = done.stdout.split()
        assert (backend, asked) == ("window", str(core == "1"))
        assert int(mask) & expected


def test_opengl_imported_first_on_x11_renders_in_a_hidden_window():
    # PyOpenGL binds to GLX on X11 when nothing chose first: the chooser takes a hidden
    # window on that platform rather than refusing (without a display it still refuses:
    # tests/gl/test_opengl_first.py)
    code = (
        "import OpenGL.GL\nimport mirrorlab\n"
        "from mirrorlab.gl.context import loaded_platform\n"
        "print(mirrorlab.render(size=(24, 16)).shape, loaded_platform())"
    )
    done = python(code, DISPLAY=_display())
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "(16, 24, 3) glx"
