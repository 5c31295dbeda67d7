"""OpenGL imported before mirrorlab, bound to GLX as PyOpenGL does on X11: a window (the
demo's context) works in that process, so does a hidden window for offscreen frames, and
EGL forced says in one line that it needs a process of its own or EGL."""

from __future__ import annotations

import os
import subprocess
import sys

CODE = """
import OpenGL.GL
from mirrorlab.errors import GLContextError
from mirrorlab.gl.context import offscreen_context, window_context
window = window_context(48, 32, "opengl first")
hidden = offscreen_context()  # bound to GLX with a display: a hidden window
print(window.backend, hidden.backend)
from OpenGL import GL
print(GL.glGetString(GL.GL_RENDERER).decode())
hidden.release()
window.release()
try:
    offscreen_context(backend="egl")
except GLContextError as exc:
    print(exc)
"""


def test_a_window_works_after_opengl_was_imported_first():
    env = {
        k: v for k, v in os.environ.items() if k not in ("PYOPENGL_PLATFORM", "XDG_SESSION_TYPE")
    }
    done = subprocess.run(
        [sys.executable, "-c", CODE], capture_output=True, text=True, timeout=120, env=env
    )
    assert done.returncode == 0, done.stderr
    backend, renderer, message = done.stdout.strip().splitlines()
    assert backend == "window hidden-window"
    assert renderer.startswith("llvmpipe")
    assert message.startswith("OpenGL was imported before mirrorlab chose its platform")
    assert "needs 'egl': import mirrorlab.gl before OpenGL" in message
