"""A program that imports OpenGL itself, before mirrorlab: it works when PyOpenGL is bound
to EGL (``import mirrorlab.gl`` first, ``PYOPENGL_PLATFORM=egl``, or PyOpenGL's own choice
on Wayland), and otherwise rendering says in one line what to do. Each case is a fresh
interpreter: PyOpenGL binds a process once."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

RENDER = "import mirrorlab\nprint(mirrorlab.render(size=(24, 16)).shape)"


def run(code: str, **env: str) -> subprocess.CompletedProcess:
    clean = {
        k: v
        for k, v in os.environ.items()
        if k not in ("PYOPENGL_PLATFORM", "EGL_PLATFORM", "XDG_SESSION_TYPE")
    }
    return subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        timeout=120,
        env={**clean, **env},
    )


@pytest.mark.parametrize(
    "before, env",
    [
        ("import mirrorlab.gl\nimport OpenGL.GL", {}),
        ("import OpenGL.GL", {"PYOPENGL_PLATFORM": "egl"}),
        ("import OpenGL.GL", {"XDG_SESSION_TYPE": "wayland"}),  # PyOpenGL picks EGL itself
    ],
)
def test_opengl_imported_first_works_when_bound_to_egl(before, env):
    done = run(f"{before}\n{RENDER}", **env)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "(16, 24, 3)"


@pytest.mark.parametrize("before", ["import OpenGL.GL", "import mirrorlab\nimport OpenGL.GL"])
def test_opengl_bound_to_glx_first_says_what_to_do_in_one_line(before):
    code = (
        f"{before}\nimport mirrorlab\n"
        "try:\n    mirrorlab.render(size=(24, 16))\n"
        "except mirrorlab.errors.GLContextError as exc:\n    print(exc)\n"
    )
    done = run(code)
    assert done.returncode == 0, done.stderr
    message = done.stdout.strip()
    assert "\n" not in message
    assert message == (
        "OpenGL was imported before mirrorlab chose its platform, and "
        "PyOpenGL bound this process to 'glx'; headless rendering needs "
        "'egl': import mirrorlab.gl before OpenGL, or set "
        "PYOPENGL_PLATFORM=egl before Python starts"
    )
    # and the advice works
    assert run(f"import mirrorlab.gl\n{before}\n{RENDER}").returncode == 0
