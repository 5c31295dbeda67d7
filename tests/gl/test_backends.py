"""The offscreen backends chosen and forced, headless (no display): EGL forced and asked
for as a 4.1 core context, and the one-line errors of a bad variable and of a hidden
window forced without a display (a machine with neither EGL nor a display:
test_faults.py). Each case is a fresh process: PyOpenGL binds a process once. The
hidden-window backend, which needs a display, is tested in tests/window."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

PROBE = """
from mirrorlab.gl.context import loaded_platform, offscreen_context
with offscreen_context() as context:
    from OpenGL import GL
    from OpenGL.error import GLError
    mask = int(GL.glGetIntegerv(GL.GL_CONTEXT_PROFILE_MASK))
    flags = int(GL.glGetIntegerv(GL.GL_CONTEXT_FLAGS))
    try:
        GL.glMatrixMode(GL.GL_MODELVIEW)
        legacy = "matrix-mode"
    except GLError:
        legacy = "no-matrix-mode"
    print(context.backend, context.core, loaded_platform(), mask, flags, legacy)
"""
CORE_PROFILE_BIT, COMPATIBILITY_PROFILE_BIT, FORWARD_COMPATIBLE_BIT = 0x1, 0x2, 0x1
VARIABLES = (
    "PYOPENGL_PLATFORM",
    "EGL_PLATFORM",
    "MIRRORLAB_GL_BACKEND",
    "MIRRORLAB_GL_CORE",
    "DISPLAY",
    "WAYLAND_DISPLAY",
    "XDG_SESSION_TYPE",
)


def environment(**env: str) -> dict[str, str]:
    return {**{k: v for k, v in os.environ.items() if k not in VARIABLES}, **env}


def python(code: str, prefix: tuple[str, ...] = (), **env: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [*prefix, sys.executable, "-c", code],
        capture_output=True,
        text=True,
        timeout=300,
        env=environment(**env),
    )


def mirrorlab(*args: str, prefix: tuple[str, ...] = (), **env: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [*prefix, sys.executable, "-m", "mirrorlab", *args],
        capture_output=True,
        text=True,
        timeout=300,
        env=environment(**env),
    )


def hide_egl() -> tuple[str, ...]:
    """A bwrap prefix that runs a command with libEGL.so.1 replaced by an empty file."""
    if shutil.which("bwrap") is None and not os.environ.get("CI"):
        pytest.skip("bubblewrap (Debian bwrap) is needed to hide libEGL.so.1")
    listing = subprocess.run(
        ["/sbin/ldconfig", "-p"], capture_output=True, text=True, check=True
    ).stdout
    paths = {
        line.split("=>")[-1].strip()
        for line in listing.splitlines()
        if line.strip().startswith("libEGL.so.1 ")
    }
    assert paths, "ldconfig -p lists no libEGL.so.1"
    hidden: tuple[str, ...] = ("bwrap", "--dev-bind", "/", "/")
    for path in sorted(paths):
        hidden += ("--ro-bind", "/dev/null", os.path.realpath(path))
    return hidden


def png(path) -> np.ndarray:
    with Image.open(path) as image:
        return np.asarray(image.convert("RGB"))


def probe(**env: str) -> list[str]:
    done = python(PROBE, (), **env)
    assert done.returncode == 0, done.stderr
    return done.stdout.split()


@pytest.mark.parametrize("backend", ["", "auto", "egl"])
def test_egl_is_chosen_headless_and_can_be_forced(backend):
    fields = probe(MIRRORLAB_GL_BACKEND=backend)
    assert fields[:3] == ["egl", "False", "egl"]
    assert int(fields[3]) & COMPATIBILITY_PROFILE_BIT
    assert fields[5] == "matrix-mode"


def test_the_core_variable_gives_a_core_forward_compatible_egl_context():
    backend, core, platform, mask, flags, legacy = probe(
        MIRRORLAB_GL_BACKEND="egl", MIRRORLAB_GL_CORE="1"
    )
    assert (backend, core, platform) == ("egl", "True", "egl")
    assert int(mask) & CORE_PROFILE_BIT and not int(mask) & COMPATIBILITY_PROFILE_BIT
    assert int(flags) & FORWARD_COMPATIBLE_BIT
    assert legacy == "no-matrix-mode"  # the fixed pipeline is gone


def test_the_default_frame_is_the_same_in_a_core_context(tmp_path):
    for name, core in (("compatibility", "0"), ("core", "1")):
        done = mirrorlab(
            "render",
            "--size",
            "96x64",
            "--out",
            str(tmp_path / f"{name}.png"),
            MIRRORLAB_GL_CORE=core,
        )
        assert done.returncode == 0, done.stderr
    assert np.array_equal(png(tmp_path / "compatibility.png"), png(tmp_path / "core.png"))


@pytest.mark.parametrize(
    "variable, value, message",
    [
        (
            "MIRRORLAB_GL_BACKEND",
            "glx",
            "MIRRORLAB_GL_BACKEND='glx' is not a backend; expected one of auto, egl, hidden-window",
        ),
        (
            "MIRRORLAB_GL_CORE",
            "yes",
            "MIRRORLAB_GL_CORE='yes' is not allowed; expected 1 (ask "
            "for an OpenGL 4.1 core context) or 0",
        ),
    ],
)
def test_a_bad_variable_is_one_line_and_exit_2(tmp_path, variable, value, message):
    done = mirrorlab(
        "render", "--size", "32x32", "--out", str(tmp_path / "x.png"), **{variable: value}
    )
    assert done.returncode == 2
    assert done.stderr == f"mirrorlab render: error: {message}\n"
    assert not (tmp_path / "x.png").exists()


def test_a_hidden_window_forced_without_a_display_says_what_to_do(tmp_path):
    done = mirrorlab(
        "render",
        "--size",
        "32x32",
        "--out",
        str(tmp_path / "x.png"),
        MIRRORLAB_GL_BACKEND="hidden-window",
    )
    assert done.returncode == 1
    assert done.stderr == (
        "mirrorlab render: error: MIRRORLAB_GL_BACKEND=hidden-window "
        "needs a display (DISPLAY is not set); run under 'xvfb-run -a', "
        "or unset it to render with EGL\n"
    )


def test_the_checker_process_is_pinned_to_the_backend_chosen_here(monkeypatch):
    from mirrorlab.labs.trusted.gl_process import gl_process_environment

    monkeypatch.setenv("PYOPENGL_PLATFORM", "glx")
    monkeypatch.setenv("DISPLAY", ":99")
    monkeypatch.setenv("MIRRORLAB_GL_BACKEND", "hidden-window")
    env = gl_process_environment()
    assert env["MIRRORLAB_GL_BACKEND"] == "hidden-window"
    assert "PYOPENGL_PLATFORM" not in env  # the process chooses it from the backend
    monkeypatch.delenv("MIRRORLAB_GL_BACKEND")
    monkeypatch.delenv("DISPLAY")
    monkeypatch.setenv("EGL_PLATFORM", "x11")
    env = gl_process_environment()
    assert (env["MIRRORLAB_GL_BACKEND"], env["EGL_PLATFORM"]) == ("egl", "surfaceless")
