"""A GL error is caught where it happens and named: the pass it happened in, the GL error,
and (in a debug context, as every GL test's is) the driver's own message."""

from __future__ import annotations

import pytest

import mirrorlab
from mirrorlab.errors import GLOutOfMemoryError, GLPassError
from mirrorlab.gl.context import gl_pass
from mirrorlab.gl.opengl import GL
from tests.gl.frames import draw

BAD_CAPABILITY = 0xDEAD


def test_a_gl_error_in_a_pass_names_the_pass_and_the_driver_message():
    with pytest.raises(GLPassError) as caught, gl_pass("a test pass"):
        GL.glEnable(BAD_CAPABILITY)
    error = caught.value
    assert error.pass_name == "a test pass" and error.code == GL.GL_INVALID_ENUM
    message = str(error)
    assert message.startswith("OpenGL error GL_INVALID_ENUM in pass 'a test pass': glEnable")
    assert "0xdead" in message.lower(), f"no driver message in {message!r}"
    assert GL.glGetError() == GL.GL_NO_ERROR


def test_out_of_memory_is_its_own_kind():
    with pytest.raises(GLOutOfMemoryError, match="ran out of memory in pass 'huge'"):
        with gl_pass("huge"):
            cube = GL.glGenTextures(1)
            try:
                GL.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, cube)
                GL.glTexImage2D(
                    GL.GL_TEXTURE_CUBE_MAP_POSITIVE_X,
                    0,
                    GL.GL_RGB8,
                    16384,
                    16384,
                    0,
                    GL.GL_RGB,
                    GL.GL_UNSIGNED_BYTE,
                    None,
                )
            finally:
                GL.glDeleteTextures([cube])
    assert isinstance(GLOutOfMemoryError("p", 0x505, "d"), ValueError)  # bad input: exit 2


@pytest.mark.parametrize(
    ("scene", "method", "failing"),
    [
        ("lab20", "ortho", "capture:mirror"),
        ("lab20", "stencil", "camera"),
        ("mirror_and_sphere", None, "capture:sphere"),
    ],
)
def test_the_renderer_names_the_pass_that_failed(scene_renderer, scene, method, failing):
    loaded = mirrorlab.api.resolve_scene(scene, method=method)
    draw(scene_renderer, loaded, (32, 32))  # passes made; now make one of them fail
    name = failing.split(":")[1] if ":" in failing else loaded.reflectors[0].name
    broken = scene_renderer.pass_for(name)
    method_name = "update" if failing.startswith("capture") else "draw"
    original = getattr(broken, method_name)

    def fail_then_run(*args, **kwargs):
        GL.glEnable(BAD_CAPABILITY)
        return original(*args, **kwargs)

    setattr(broken, method_name, fail_then_run)
    moved = loaded.with_angles((10.0, 20.0, -30.0)) if loaded.robot else loaded
    changed = mirrorlab.api.resolve_scene(moved, camera=(9.0, 4.0, 8.0))
    with pytest.raises(GLPassError) as caught:
        draw(scene_renderer, changed, (32, 32), use_plan=False)
    assert caught.value.pass_name == failing
    # The renderer forgot what the failed frame half made, and GL is usable again.
    assert scene_renderer.state.held == {}
    setattr(broken, method_name, original)
    image, _ = draw(scene_renderer, changed, (32, 32))
    assert image.std() > 0
