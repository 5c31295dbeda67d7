"""The labs' legacy calls as the trusted side carries them out on a core context
(labs/trusted/legacy.py), against Mesa's own compatibility pipeline in this (compatibility)
context: the same matrices after every matrix call, the same errors at the stacks' ends;
and the GLSL translation of the compatibility built-ins (labs/trusted/compat_glsl.py)."""

from __future__ import annotations

import numpy as np
import pytest
from OpenGL import GLU
from OpenGL.error import GLError

from mirrorlab.errors import GLPassError
from mirrorlab.gl.context import check_gl_errors
from mirrorlab.gl.opengl import GL
from mirrorlab.labs.trusted.calls import CallError
from mirrorlab.labs.trusted.compat_glsl import translate_compat_glsl
from mirrorlab.labs.trusted.legacy import (
    FixedFunction,
    look_at,
    multiply,
    ortho,
    perspective,
    translation,
)


def _native(mode: int) -> np.ndarray:
    name = GL.GL_MODELVIEW_MATRIX if mode == GL.GL_MODELVIEW else GL.GL_PROJECTION_MATRIX
    return np.asarray(GL.glGetFloatv(name), dtype=np.float32).reshape(4, 4).T


def _random_call(rng: np.random.Generator) -> tuple[str, tuple]:
    kind = rng.integers(0, 9)
    v = [float(x) for x in np.round(rng.uniform(-8, 8, 9), int(rng.integers(0, 4)))]
    if kind == 0:
        return "glLoadIdentity", ()
    if kind == 1:
        return "glOrtho", (
            v[0],
            v[0] + 1 + abs(v[1]),
            v[2],
            v[2] + 1 + abs(v[3]),
            float(rng.choice([0.0, 0.1, v[4]])),
            15.0 + abs(v[5]),
        )
    if kind == 2:
        return "glFrustum", (
            v[0],
            v[0] + 1 + abs(v[1]),
            v[2],
            v[2] + 1 + abs(v[3]),
            0.05 + abs(v[4]) / 10,
            20.0 + abs(v[5]),
        )
    if kind == 3:
        return "glTranslatef", tuple(v[:3])
    if kind == 4:
        axis = [(1, 0, 0), (0, -1, 0), (0, 0, 1), tuple(v[1:4])][int(rng.integers(0, 4))]
        return "glRotatef", (v[0] * 20, *map(float, axis))
    if kind == 5:
        return "glScalef", tuple(x if x else 1.0 for x in v[:3])
    if kind == 6:
        return "gluLookAt", tuple(v[:3]) + tuple(v[3:6]) + (0.0, 1.0, 0.0)
    if kind == 7:
        return "gluPerspective", (
            float(rng.choice([30.0, 45.0, 90.0, 60.5])),
            float(rng.uniform(0.5, 2)),
            0.1,
            100.0,
        )
    return "glMultMatrixd", (list(np.round(rng.uniform(-2, 2, 16), 3)),)


def test_matrix_calls_give_mesas_matrices(gl_context):
    """2,000 random matrix calls on both stacks, with pushes and pops, each from the matrix
    Mesa holds then: the emulated result equals Mesa's bit for bit, but glRotate's sine and
    cosine (numpy's against the C library's, one float32 rounding; measured 8e-8 of the
    matrix's largest entry)."""
    emulation = FixedFunction()
    rng = np.random.default_rng(38)
    depth = {GL.GL_MODELVIEW: 1, GL.GL_PROJECTION: 1}
    worst: dict[str, float] = {}
    for _ in range(2000):
        mode = int(rng.choice([GL.GL_MODELVIEW, GL.GL_PROJECTION]))
        GL.glMatrixMode(mode)
        emulation.glMatrixMode(mode)
        if rng.random() < 0.1 and depth[mode] < 8:
            GL.glPushMatrix()
            emulation.glPushMatrix()
            depth[mode] += 1
        elif rng.random() < 0.1 and depth[mode] > 1:
            GL.glPopMatrix()
            emulation.glPopMatrix()
            depth[mode] -= 1
        name, args = _random_call(rng)
        emulation.top(mode)[:] = _native(mode)  # each call alone, from Mesa's matrix
        getattr(GLU if name.startswith("glu") else GL, name)(*args)
        getattr(emulation, name)(*args)
        native, emulated = _native(mode), emulation.top(mode)
        scale = max(float(np.abs(native).max()), 1e-30)
        worst[name] = max(worst.get(name, 0.0), float(np.abs(native - emulated).max()) / scale)
        if mode == GL.GL_PROJECTION and rng.random() < 0.3:
            GL.glLoadIdentity()  # keep the products from growing without end
            emulation.glLoadIdentity()
        if mode == GL.GL_MODELVIEW and depth[mode] == 1 and rng.random() < 0.3:
            GL.glLoadIdentity()
            emulation.glLoadIdentity()
    for mode in depth:
        GL.glMatrixMode(mode)
        for _ in range(depth[mode] - 1):
            GL.glPopMatrix()
        GL.glLoadIdentity()
    GL.glMatrixMode(GL.GL_MODELVIEW)
    assert len(worst) == 9 and worst.pop("glRotatef") < 2e-7
    assert all(value == 0.0 for value in worst.values()), worst


def test_a_mirror_on_the_near_plane_lands_where_mesa_puts_it():
    """Lab 20's quad in its own capture: eye z exactly 0 with glOrtho(..., 0, 15), clip z
    exactly -1 in float32, as Mesa's float arithmetic gives it (a double product would put
    it just outside and clip the quad)."""
    projection = ortho(-6, 2, -3, 5, 0, 15)
    assert projection is not None
    mvp = multiply(
        multiply(projection, look_at((-7, 0, 0), (0, 0, 0), (0, 1, 0))),
        translation(7, 0, 0),
    )
    corner = np.array([-7, -3, -6, 1], dtype=np.float32)
    clip = [np.float32(0)] * 4
    for row in range(4):
        total = np.float32(0)
        for col in range(4):
            total = np.float32(total + mvp[row, col] * corner[col])
        clip[row] = total
    assert clip[2] == np.float32(-1.0) and clip[3] == np.float32(1.0)
    assert perspective(45, 1, 1, 1) is None


def test_the_stacks_end_where_mesas_do(gl_context):
    emulation = FixedFunction()
    for mode, depth in ((GL.GL_MODELVIEW, 32), (GL.GL_PROJECTION, 32)):
        GL.glMatrixMode(mode)
        emulation.glMatrixMode(mode)
        for _ in range(depth - 1):
            GL.glPushMatrix()
            emulation.glPushMatrix()
        with pytest.raises(GLError) as native:
            GL.glPushMatrix()
        with pytest.raises(CallError) as emulated:
            emulation.glPushMatrix()
        assert int(native.value.err) == emulated.value.err == 0x0503
        for _ in range(depth - 1):
            GL.glPopMatrix()
            emulation.glPopMatrix()
        with pytest.raises(GLError) as native:
            GL.glPopMatrix()
        with pytest.raises(CallError) as emulated:
            emulation.glPopMatrix()
        assert int(native.value.err) == emulated.value.err == 0x0504
    with pytest.raises(GLPassError, match="GL_STACK_OVERFLOW"):  # and the debug log's
        check_gl_errors("the stacks' ends")
    GL.glMatrixMode(GL.GL_MODELVIEW)
    with pytest.raises(CallError) as emulated:
        emulation.glOrtho(1, 1, 0, 1, 0, 1)
    assert emulated.value.err == 0x0501


def test_translation_keeps_the_students_names_and_lines():
    student = (
        "// gl_Vertex in a comment stays\n"
        "vec3 my_gl_Normal = vec3(0.0);\n"
        "vec3 reflect_eye(vec3 u, vec3 n) {\n"
        "    vec4 e = gl_ModelViewMatrix * vec4(u, 1.0);\n"
        "    return e.xyz + texture2D(gl_ModelViewMatrixInverse_, u.xy).rgb;\n"
        "}\n"
    )
    out = translate_compat_glsl(student, "fragment")
    lines = out.split("\n")
    assert lines[0] == "uniform mat4 ml_ModelViewMatrix;" and lines[1] == "#line 1"
    assert lines[2:] == student.replace("gl_ModelViewMatrix *", "ml_ModelViewMatrix *").replace(
        "texture2D", "texture"
    ).split("\n")
    assert "my_gl_Normal" in out and "gl_ModelViewMatrixInverse_" in out
    assert "// gl_Vertex in a comment stays" in out
    assert translate_compat_glsl("int f() { return 1; }", "vertex") == "int f() { return 1; }"


def test_translated_kit_shader_compiles_as_core(gl_context):
    """A whole compatibility shader (its #version line too) becomes GLSL 330 core that
    compiles, attributes at the locations the emulated glBegin feeds."""
    source = (
        "#version 330 compatibility\n"
        "out vec2 st;\n"
        "void main() {\n"
        "    st = gl_MultiTexCoord0.st;\n"
        "    gl_Position = gl_ModelViewProjectionMatrix * gl_Vertex;\n"
        "}\n"
    )
    out = translate_compat_glsl(source, "vertex")
    assert out.startswith("#version 330 core\n")
    assert "layout(location = 0) in vec4 ml_Vertex;" in out
    assert "layout(location = 4) in vec4 ml_MultiTexCoord0;" in out
    shader = GL.glCreateShader(GL.GL_VERTEX_SHADER)
    GL.glShaderSource(shader, out)
    GL.glCompileShader(shader)
    compiled = GL.glGetShaderiv(shader, GL.GL_COMPILE_STATUS)
    log = GL.glGetShaderInfoLog(shader)
    GL.glDeleteShader(shader)
    assert compiled, log
