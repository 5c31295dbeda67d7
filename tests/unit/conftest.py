"""Unit tests are numpy only: a test that makes OpenGL or glfw load fails."""

from __future__ import annotations

import sys

import pytest

GL_PACKAGES = ("OpenGL", "glfw")


def gl_modules() -> set[str]:
    return {name for name in sys.modules if name.split(".")[0] in GL_PACKAGES}


@pytest.fixture(autouse=True)
def no_opengl_in_unit_tests():
    """Fails the test that first loads OpenGL or glfw into this process (a run that mixes
    in GL tests, which load them first, is not checked)."""
    before = gl_modules()
    yield
    if not before:
        loaded = gl_modules()
        assert not loaded, f"a unit test loaded {sorted(loaded)[:3]}; unit tests are numpy only"
