"""Headless GL fixtures: one offscreen context per test session (EGL, or the backend
MIRRORLAB_GL_BACKEND names), GL errors checked and state reset around every test."""

from __future__ import annotations

import pytest

from mirrorlab.gl.context import offscreen_context
from mirrorlab.gl.opengl import GL


@pytest.fixture(scope="session")
def gl_context():
    """A debug context: its KHR_debug messages are checked after every pass the renderer
    runs (and PyOpenGL checks glGetError after every call), so a GL error fails the test
    where it happens, naming the pass."""
    with offscreen_context(debug=True) as context:
        yield context


@pytest.fixture(autouse=True)
def clean_gl_state(gl_context):
    """No GL error may be pending before or left after a test; resources made by the test
    are released, and bindings reset for the next one."""
    gl_context.make_current()
    assert GL.glGetError() == GL.GL_NO_ERROR, "a GL error was pending before the test"
    live_before = len(gl_context.resources)
    yield
    error = GL.glGetError()
    GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)
    GL.glUseProgram(0)
    GL.glBindVertexArray(0)
    GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
    assert error == GL.GL_NO_ERROR, f"test left GL error {error:#x}"
    assert len(gl_context.resources) == live_before, "test did not release its GL resources"


@pytest.fixture
def registry(gl_context):
    """The context's resource registry; whatever a test makes in it is released after."""
    yield gl_context.resources
    gl_context.resources.release_all()


@pytest.fixture
def scene_renderer(registry):
    """A :class:`mirrorlab.renderer.SceneRenderer` on the session's context, released
    after the test (with everything else the test made in the registry)."""
    from mirrorlab.renderer import SceneRenderer

    renderer = SceneRenderer(registry)
    yield renderer
    renderer.release()


def module_context():
    """A context of a test module's own, to replace the session's there (a module uses it
    as ``gl_context = pytest.fixture(scope="module")(module_context)``): for tests whose
    student calls leave GL state, and GL errors in the debug log, that no other test may
    see."""
    with offscreen_context() as context:
        yield context
