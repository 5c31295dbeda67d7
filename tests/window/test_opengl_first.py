"""OpenGL imported before mirrorlab, bound to GLX as PyOpenGL does on X11: a window (the
demo's context) works in that process, and headless rendering says in one line that it
needs a process of its own or EGL."""

from __future__ import annotations

import os
import subprocess
import sys

CODE = """
import OpenGL.GL
from mirrorlab.errors import GLContextError
from mirrorlab.gl.context import HeadlessContext, WindowContext
window = WindowContext(48, 32, "opengl first", visible=False)
from OpenGL import GL
print(GL.glGetString(GL.GL_RENDERER).decode())
window.release()
try:
    HeadlessContext()
except GLContextError as exc:
    print(exc)
"""


def test_a_window_works_after_opengl_was_imported_first():
    env = {k: v for k, v in os.environ.items() if k not in ("PYOPENGL_PLATFORM",
                                                             "XDG_SESSION_TYPE")}
    done = subprocess.run([sys.executable, "-c", CODE], capture_output=True, text=True,
                          timeout=120, env=env)
    assert done.returncode == 0, done.stderr
    renderer, message = done.stdout.strip().splitlines()
    assert renderer.startswith("llvmpipe")
    assert message.startswith("OpenGL was imported before mirrorlab chose its platform")
    assert "needs 'egl': import mirrorlab.gl before OpenGL" in message
