"""The labs' executor, fed messages directly in a headless context (no sandbox): each call
is checked before it runs, refused in the words PyOpenGL would use, and noted with the
student's line; pixel data must hold what GL will read, and be zeros
(tests/gl/test_lab_channels.py tries every channel); copies keep the picture they copied;
every limit ends the run with one line; the lab's own objects are out of reach."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import Framebuffer
from mirrorlab.labs.lab20_mirror.trusted import Lab20
from mirrorlab.labs.lab_spheremap.trusted import SphereMapLab
from mirrorlab.labs.trusted.call_executor import Executor, RunLimits, Stop
from mirrorlab.labs.trusted.session import open_session
from mirrorlab.labs.trusted.variants import default_variant

SIZE = (64, 64)


@pytest.fixture
def context(registry):
    """A 64 x 64 target of the session's context, bound."""
    target = Framebuffer(registry, *SIZE)
    target.bind()
    return target


def executor(lab: str = "lab20", limits: RunLimits | None = None) -> Executor:
    return Executor(open_session(lab, SIZE, default_variant(lab)), limits)


def call(ex: Executor, name: str, *args, arrays=(), op: str = "gl", line: int = 1):
    reply, payloads = ex.call(
        {"op": op, "fn": name, "args": list(args), "line": line}, list(arrays)
    )
    return reply, payloads


def test_a_call_runs_and_its_line_is_noted(context):
    ex = executor()
    reply, _ = call(ex, "glMatrixMode", int(GL.GL_PROJECTION), line=7)
    assert reply == {"ok": True, "value": None}
    assert int(GL.glGetIntegerv(GL.GL_MATRIX_MODE)) == GL.GL_PROJECTION
    assert (ex.tracker.matrix_mode.value, ex.tracker.matrix_mode.line) == (GL.GL_PROJECTION, 7)
    reply, _ = call(ex, "glOrtho", -6, 2, -3, 5, 0, 15, line=8)
    assert reply["ok"] and ex.tracker.matrix_ops[int(GL.GL_PROJECTION)][-1]["line"] == 8
    GL.glMatrixMode(GL.GL_MODELVIEW)


def test_calls_are_refused_before_they_run(context):
    ex = executor()
    cases: list[tuple[tuple[Any, ...], str, str]] = [
        (("glDrawPixels", 1, 1, 0, 0, None), "NotImplementedError", "not one of the OpenGL"),
        (("glMatrixMode", 12345), "GLError", "invalid enumerant"),
        (("glOrtho", -6, 2, -3, 5, 0), "TypeError", "takes 6 arguments"),
        (("glOrtho", -6, 2, "x", 5, 0, 15), "TypeError", "expected a number"),
        (("glLoadMatrixf", [1.0] * 15), "ValueError", "expected 16 numbers"),
        (("glViewport", 0, 0, 99999, 10), "GLError", "outside 0..1024"),
        (("glPixelStorei", int(GL.GL_UNPACK_ROW_LENGTH), 4), "GLError", "invalid enumerant"),
    ]
    before = np.asarray(GL.glGetIntegerv(GL.GL_VIEWPORT)).tolist()
    for (name, *args), kind, words in cases:
        reply, _ = call(ex, name, *args)
        assert not reply["ok"] and reply["type"] == kind and words in reply["message"], (
            name,
            reply,
        )
    assert np.asarray(GL.glGetIntegerv(GL.GL_VIEWPORT)).tolist() == before
    assert int(GL.glGetError()) == GL.GL_NO_ERROR
    assert len(ex.call_errors) == len(cases)


def test_pixel_data_must_hold_what_gl_reads_and_be_zeros(context):
    ex = executor()
    (texture,) = [call(ex, "glGenTextures", 1)[0]["value"]]
    assert call(ex, "glBindTexture", int(GL.GL_TEXTURE_2D), texture)[0]["ok"]
    image = (
        int(GL.GL_TEXTURE_2D),
        0,
        int(GL.GL_RGB),
        5,
        4,
        0,
        int(GL.GL_RGB),
        int(GL.GL_UNSIGNED_BYTE),
        {"$a": 0},
    )
    # 5 pixels of 3 bytes: rows of 15 bytes padded to 16 at GL_UNPACK_ALIGNMENT 4
    short = np.zeros(5 * 4 * 3, dtype=np.uint8)
    reply, _ = call(ex, "glTexImage2D", *image, arrays=[short])
    assert not reply["ok"] and "GL would read 63" in reply["message"]
    assert call(ex, "glTexImage2D", *image, arrays=[np.zeros(63, dtype=np.uint8)])[0]["ok"]
    picture = np.full(63, 200, dtype=np.uint8)
    reply, _ = call(ex, "glTexImage2D", *image, arrays=[picture])
    assert reply["type"] == "ValueError" and "no pixels of a file's own" in reply["message"]
    blank = (*image[:-1], None)
    assert call(ex, "glTexImage2D", *blank)[0]["ok"]
    assert ex.tracker.textures[texture].images[(0, 0)].source == "blank"


def _quad(ex: Executor) -> None:
    call(ex, "glBegin", int(GL.GL_QUADS))
    for x, y in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
        call(ex, "glVertex3f", x, y, 0)
    reply, _ = call(ex, "glEnd")
    assert reply["ok"], reply


def test_copies_keep_the_picture_copied(context):
    ex = executor()
    capture = call(ex, "glGenTextures", 1)[0]["value"]
    ex.begin_frame()
    _quad(ex)
    call(ex, "glBindTexture", int(GL.GL_TEXTURE_2D), capture)
    copy = (int(GL.GL_TEXTURE_2D), 0, int(GL.GL_RGB), 0, 0, 64, 64, 0)
    assert call(ex, "glCopyTexImage2D", *copy)[0]["ok"]
    call(ex, "glClear", int(GL.GL_COLOR_BUFFER_BIT))
    assert call(ex, "glCopyTexImage2D", *copy)[0]["ok"]
    assert ex.tracker.textures[capture].images[(0, 0)].source == "copy"
    copies = [e for e in ex.tracker.frames[-1]["events"] if e["kind"] == "copy"]
    assert [e["picture"] for e in copies] == ["copy_0_0", "copy_0_1"]
    assert ex.pictures["copy_0_0"].shape == (64, 64, 3)
    call(ex, "glBindTexture", int(GL.GL_TEXTURE_2D), 0)


def test_the_labs_own_objects_are_out_of_reach(context):
    ex = executor("spheremap")
    assert isinstance(ex.session, SphereMapLab)
    backdrop = ex.session.backdrop_texture
    for name, args in (
        ("glBindTexture", (int(GL.GL_TEXTURE_2D), backdrop)),
        ("glDeleteTextures", ([backdrop],)),
        ("glUseProgram", (ex.session.scene_program,)),
    ):
        reply, _ = call(ex, name, *args)
        assert not reply["ok"] and reply["type"] == "GLError", (name, reply)
    assert GL.glIsTexture(backdrop)
    reply, _ = call(ex, "load_picture_texture", backdrop, "launch", op="kit")
    assert not reply["ok"] and "not a texture this file made" in reply["message"]
    reply, _ = call(
        ex,
        "load_picture_texture",
        call(ex, "glGenTextures", 1)[0]["value"],
        "../../etc/passwd",
        op="kit",
    )
    assert not reply["ok"] and "no picture" in reply["message"]


def test_kit_calls_are_recorded_and_refused_inside_glbegin(context):
    ex = executor()
    ex.begin_frame()
    reply, _ = call(ex, "draw_scene", {"textures": {"base": None}}, op="kit", line=42)
    assert reply["ok"]
    draws = [e for e in ex.tracker.frames[-1]["events"] if e["kind"] == "draw"]
    assert draws[-1]["who"] == "draw_scene" and draws[-1]["line"] == 42
    assert np.asarray(draws[-1]["projection"]).shape == (4, 4)
    call(ex, "glBegin", int(GL.GL_TRIANGLES))
    reply, _ = call(ex, "draw_scene", {"textures": {}}, op="kit")
    assert not reply["ok"] and "between glBegin and glEnd" in reply["message"]
    call(ex, "glEnd")
    reply, _ = call(ex, "draw_scene", {"textures": {"base": 9999}}, op="kit")
    assert not reply["ok"] and reply["type"] == "LabSetupError"


def test_queries_return_what_pyopengl_would(context):
    ex = executor()
    reply, payloads = call(ex, "glGetIntegerv", int(GL.GL_VIEWPORT))
    assert reply["value"]["as"] == "array" and payloads[0][1] == [4]
    reply, payloads = call(ex, "glGetString", int(GL.GL_VERSION))
    assert reply["value"]["as"] == "bytes" and payloads[0][2][:1].isdigit()
    reply, _ = call(ex, "glGetIntegerv", int(GL.GL_ACTIVE_TEXTURE))
    assert reply["value"] == int(GL.GL_TEXTURE0)


def test_each_limit_ends_the_run_in_one_line(context):
    ex = executor(limits=RunLimits(calls=5))
    for _ in range(5):
        call(ex, "glFlush")
    with pytest.raises(Stop, match="stopped after 5 calls"):
        call(ex, "glFlush")
    ex = executor(limits=RunLimits(frame_vertices=3))
    ex.begin_frame()
    call(ex, "glBegin", int(GL.GL_TRIANGLES))
    for _ in range(3):
        call(ex, "glVertex2f", 0, 0)
    with pytest.raises(Stop, match="more than 3 vertices in one frame"):
        call(ex, "glVertex2f", 0, 0)
    GL.glEnd()
    ex = executor(limits=RunLimits(textures=2))
    reply, _ = call(ex, "glGenTextures", 3)
    assert not reply["ok"] and "more than 2 textures" in reply["message"]
    ex = executor(limits=RunLimits(texture_bytes=1 << 16))
    texture = call(ex, "glGenTextures", 1)[0]["value"]
    call(ex, "glBindTexture", int(GL.GL_TEXTURE_2D), texture)
    reply, _ = call(
        ex,
        "glTexImage2D",
        int(GL.GL_TEXTURE_2D),
        0,
        int(GL.GL_RGBA),
        256,
        256,
        0,
        int(GL.GL_RGBA),
        int(GL.GL_UNSIGNED_BYTE),
        None,
    )
    assert not reply["ok"] and "more than 0 MiB" in reply["message"]


def test_nothing_reads_back_and_set_up_draws_nothing(context):
    ex = executor()
    reply, _ = call(ex, "glReadPixels", 0, 0, 64, 64, int(GL.GL_RGB), int(GL.GL_UNSIGNED_BYTE))
    assert reply["type"] == "NotImplementedError" and "never read back" in reply["message"]
    reply, _ = call(
        ex, "glTexGeni", int(GL.GL_S), int(GL.GL_TEXTURE_GEN_MODE), int(GL.GL_SPHERE_MAP)
    )
    assert reply["type"] == "NotImplementedError" and "texgen" in reply["message"]
    ex.step({"op": "enter", "function": "load_textures", "line": 3}, ("load_textures",))
    for name, args, op in (
        ("glBegin", (int(GL.GL_QUADS),), "gl"),
        ("draw_scene", ({"textures": {}},), "kit"),
    ):
        reply, _ = call(ex, name, *args, op=op)
        assert reply["type"] == "LabSetupError" and "in load_textures()" in reply["message"], reply
    assert ex.tracker.primitive is None
    ex.step({"op": "leave", "function": "load_textures"}, ("load_textures",))
    ex.begin_frame()
    assert call(ex, "draw_scene", {"textures": {}}, op="kit")[0]["ok"]


def test_gl_errors_name_the_precondition(context):
    ex = executor()
    assert isinstance(ex.session, Lab20)
    reply, _ = call(ex, "glUniform1i", ex.session.texSampler, 1)
    assert reply["type"] == "GLError" and "call glUseProgram(program) before" in reply["message"]
    call(ex, "glUseProgram", ex.session.textureShader)
    reply, _ = call(ex, "glUniform1i", ex.session.texSampler, int(GL.GL_TEXTURE1))
    assert "the enum GL_TEXTURE1; a sampler takes the unit's number" in reply["message"]
    assert call(ex, "glUniform1i", ex.session.texSampler, 1)[0]["ok"]
    reply, _ = call(ex, "glUniform3f", ex.session.texSampler, 1.0, 2.0, 3.0)
    assert reply["type"] == "GLError" and "uniform's type" in reply["message"], reply
    call(ex, "glUseProgram", 0)
