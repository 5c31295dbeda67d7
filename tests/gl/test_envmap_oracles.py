"""numpy environment-map references, and the renderer's texgen shader, against Mesa's own
implementations, which nobody here wrote: fixed-function GL_SPHERE_MAP texgen (read back
in feedback mode) and the cube-map sampler (sampled in a fragment shader into a float
framebuffer).

Raw GL on purpose: these are oracles, not render paths. Every object made here is
deleted and every state changed is put back before the test ends.
"""

from __future__ import annotations

import ctypes
import math

import numpy as np
import pytest
from numpy.typing import ArrayLike

from mirrorlab import envmap, math3d
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import Framebuffer, expand_includes

# ---------------------------------------------------------------------------- texgen oracle

FEEDBACK_FLOATS_PER_POINT = 1 + 3 + 4 + 4  # token, window xyz, RGBA, texture strq
BOX = 100.0  # half-size of the orthographic box: every test vertex must land inside it


def mesa_texgen(
    registry,
    vertices: np.ndarray,
    normals: np.ndarray,
    modelview: np.ndarray | None = None,
    normalize: bool = False,
) -> np.ndarray:
    """Mesa's GL_SPHERE_MAP (s, t) ``(n, 2)`` for object-space ``vertices`` and ``normals``
    ``(n, 3)`` float32, drawn as points under ``modelview`` ``(4, 4)`` (identity if None),
    with ``GL_NORMALIZE`` on or off."""
    n = len(vertices)
    target = Framebuffer(registry, 4, 4)
    target.bind()
    texture = int(GL.glGenTextures(1))
    buffer = np.zeros(n * FEEDBACK_FLOATS_PER_POINT + 16, np.float32)
    GL.glActiveTexture(GL.GL_TEXTURE0)
    GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
    GL.glTexImage2D(
        GL.GL_TEXTURE_2D, 0, GL.GL_RGBA8, 1, 1, 0, GL.GL_RGBA, GL.GL_UNSIGNED_BYTE, bytes(4)
    )
    GL.glMatrixMode(GL.GL_TEXTURE)
    GL.glPushMatrix()
    GL.glLoadIdentity()
    GL.glMatrixMode(GL.GL_PROJECTION)
    GL.glPushMatrix()
    GL.glLoadIdentity()
    GL.glOrtho(-BOX, BOX, -BOX, BOX, -BOX, BOX)
    GL.glMatrixMode(GL.GL_MODELVIEW)
    GL.glPushMatrix()
    GL.glLoadMatrixd(np.ascontiguousarray((np.eye(4) if modelview is None else modelview).T))
    # Without an enabled texture Mesa drops the generated coordinates (DESIGN.md).
    GL.glEnable(GL.GL_TEXTURE_2D)
    for coord in (GL.GL_S, GL.GL_T):
        GL.glTexGeni(coord, GL.GL_TEXTURE_GEN_MODE, GL.GL_SPHERE_MAP)
    GL.glEnable(GL.GL_TEXTURE_GEN_S)
    GL.glEnable(GL.GL_TEXTURE_GEN_T)
    if normalize:
        GL.glEnable(GL.GL_NORMALIZE)
    try:
        GL.glFeedbackBuffer(buffer.size, GL.GL_3D_COLOR_TEXTURE, buffer)
        GL.glRenderMode(GL.GL_FEEDBACK)
        GL.glBegin(GL.GL_POINTS)
        for vertex, normal in zip(vertices.tolist(), normals.tolist(), strict=True):
            GL.glNormal3f(*normal)
            GL.glVertex3f(*vertex)
        GL.glEnd()
    finally:
        if GL.glGetIntegerv(GL.GL_RENDER_MODE) != GL.GL_RENDER:
            GL.glRenderMode(GL.GL_RENDER)
        # Point GL away from this numpy buffer, which is about to be freed.
        GL.glFeedbackBuffer(0, GL.GL_2D, np.zeros(1, np.float32))
        GL.glDisable(GL.GL_NORMALIZE)
        GL.glDisable(GL.GL_TEXTURE_GEN_S)
        GL.glDisable(GL.GL_TEXTURE_GEN_T)
        for coord in (GL.GL_S, GL.GL_T):
            GL.glTexGeni(coord, GL.GL_TEXTURE_GEN_MODE, GL.GL_EYE_LINEAR)  # GL's default
        GL.glDisable(GL.GL_TEXTURE_2D)
        GL.glMatrixMode(GL.GL_MODELVIEW)
        GL.glPopMatrix()
        GL.glMatrixMode(GL.GL_PROJECTION)
        GL.glPopMatrix()
        GL.glMatrixMode(GL.GL_TEXTURE)
        GL.glPopMatrix()
        GL.glMatrixMode(GL.GL_MODELVIEW)
        GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
        GL.glDeleteTextures([texture])
    records = buffer[: n * FEEDBACK_FLOATS_PER_POINT].reshape(n, FEEDBACK_FLOATS_PER_POINT)
    assert np.all(records[:, 0] == GL.GL_POINT_TOKEN), "a point was clipped or not recorded"
    assert np.all(buffer[n * FEEDBACK_FLOATS_PER_POINT :] == 0), "more feedback than points"
    assert np.all(records[:, 11] == 1), "texture q should be 1"
    return records[:, 8:10].astype(np.float64)


def random_directions(rng, count: int) -> np.ndarray:
    v = rng.normal(size=(count, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def texgen_cases(rng) -> tuple[np.ndarray, np.ndarray]:
    """Eye-space vertices and normals ``(n, 3)``: random plus structured cases."""
    vertices: list[ArrayLike] = []
    normals: list[ArrayLike] = []
    # Random positions at several distances, random normals of random length.
    for scale in (1e-3, 0.5, 3.0, 40.0):
        v = random_directions(rng, 100) * scale * rng.uniform(0.5, 1, (100, 1))
        vertices.append(v)
        normals.append(random_directions(rng, 100))
    axes = np.concatenate([np.eye(3), -np.eye(3)])
    # Axis vertices against axis normals.
    for v in axes * 2.0:
        for n in axes:
            vertices.append([v])
            normals.append([n])
    # Head-on (n = -u: r = -u), and grazing (n perpendicular to u: r = u).
    u = random_directions(rng, 60)
    vertices.append(u * 5.0)
    normals.append(-u)
    perpendicular = np.cross(u, random_directions(rng, 60))
    perpendicular /= np.linalg.norm(perpendicular, axis=1, keepdims=True)
    vertices.append(u * 5.0)
    normals.append(perpendicular)
    # Straight ahead of the eye, normals tilting from facing the eye to edge-on.
    for angle in np.linspace(0, 89, 30):
        a = math.radians(angle)
        vertices.append([[0.0, 0.0, -4.0]])
        normals.append([[math.sin(a), 0.0, math.cos(a)]])
    return (np.concatenate(vertices).astype(np.float32), np.concatenate(normals).astype(np.float32))


def compare_texgen(mesa: np.ndarray, numpy_st: np.ndarray, r_eye: np.ndarray) -> None:
    """Mesa and numpy agree to 1e-5 where the map is not steep (1 + rz >= 1e-2), and to
    2e-6 / sqrt(1 + rz) closer to the singular direction (float32 in Mesa)."""
    gap = 1 + r_eye[:, 2] / np.linalg.norm(r_eye, axis=1)
    assert np.all(gap >= 1e-6), "singular inputs must be left out of the comparison"
    tolerance = np.where(gap >= 1e-2, 1e-5, 2e-6 / np.sqrt(gap))
    error = np.abs(mesa - numpy_st).max(axis=1)
    assert np.all(np.isfinite(mesa)), "Mesa gave NaN on an input that should be regular"
    worst = int(np.argmax(error / tolerance))
    assert np.all(error <= tolerance), (
        f"{int((error > tolerance).sum())} of {len(error)} differ; worst: Mesa "
        f"{mesa[worst]}, numpy {numpy_st[worst]}, 1 + rz = {gap[worst]:.3g}"
    )


def test_sphere_map_texgen_matches_mesa_with_identity_modelview(registry):
    rng = np.random.default_rng(20)
    vertices, normals = texgen_cases(rng)
    # A zero normal: GL without GL_NORMALIZE reflects about it as given, r = u, which is
    # numpy's documented rule too.
    vertices = np.concatenate([vertices, [[0.5, -0.25, -2.0]]]).astype(np.float32)
    normals = np.concatenate([normals, [[0.0, 0.0, 0.0]]]).astype(np.float32)
    v64, n64 = vertices.astype(np.float64), normals.astype(np.float64)
    u = v64 / np.linalg.norm(v64, axis=1, keepdims=True)
    r = envmap.reflect(u, n64)
    # Leave out what Mesa turns into NaN: r = (0, 0, -1) (here the grazing rays along the
    # view axis); vertices at the eye are not in this set.
    regular = 1 + r[:, 2] >= 1e-6
    assert regular.sum() >= 400
    mesa = mesa_texgen(registry, vertices[regular], normals[regular])
    s, t = envmap.sphere_map_texgen(v64[regular], n64[regular])
    compare_texgen(mesa, np.stack([s, t], axis=1), r[regular])


def modelview_case(seed: int) -> tuple[np.ndarray, ...]:
    """Texgen inputs under a modelview with a non-uniform scale: object-space vertices
    ``(n, 3)`` and normals of random length ``(n, 3)`` (float32; GL_NORMALIZE makes GL
    normalise them after the inverse-transpose transform, as numpy's reflect does), the
    modelview ``(4, 4)``, eye-space vertices, normals and reflection vectors ``(n, 3)``
    (float64), and the mask of the regular ones (no Mesa NaN: r = (0, 0, -1) or a vertex
    at the eye), at least 400 of them."""
    rng = np.random.default_rng(seed)
    vertices, normals = texgen_cases(rng)
    normals = (normals * rng.uniform(0.2, 5, (len(normals), 1))).astype(np.float32)
    modelview = (
        math3d.translate((0.5, -1.0, -6.0))
        @ math3d.rotate(35, (1, 2, 0.5))
        @ math3d.scale((1.0, 2.0, 0.5))
    )
    # Keep object-space vertices inside the box after the transform.
    vertices = (vertices / 4).astype(np.float32)
    v_eye = math3d.transform_points(modelview, vertices.astype(np.float64))[:, :3]
    n_eye = normals.astype(np.float64) @ math3d.normal_matrix(modelview).T
    r = envmap.reflect(v_eye / np.linalg.norm(v_eye, axis=1, keepdims=True), n_eye)
    regular = (1 + r[:, 2] / np.linalg.norm(r, axis=1) >= 1e-6) & (
        np.linalg.norm(v_eye, axis=1) > 1e-6
    )
    assert regular.sum() >= 400
    return vertices, normals, modelview, v_eye, n_eye, r, regular


def test_sphere_map_texgen_matches_mesa_under_a_modelview_with_gl_normalize(registry):
    vertices, normals, modelview, v_eye, n_eye, r, regular = modelview_case(21)
    mesa = mesa_texgen(registry, vertices[regular], normals[regular], modelview, normalize=True)
    s, t = envmap.sphere_map_texgen(v_eye[regular], n_eye[regular])
    compare_texgen(mesa, np.stack([s, t], axis=1), r[regular])


def test_sphere_map_texgen_matches_mesa_close_to_the_singular_direction(registry):
    # u = (0, 0, -1) and normals tilted to within a hair of edge-on: r approaches
    # (0, 0, -1) from many azimuths, so (s, t) approaches the rim all round.
    vertex_rows, normal_rows = [], []
    for tilt in (1e-1, 1e-2, 1e-3):
        for azimuth in np.linspace(0, 2 * np.pi, 12, endpoint=False):
            n = np.array([np.cos(azimuth), np.sin(azimuth), tilt])
            vertex_rows.append([0.0, 0.0, -3.0])
            normal_rows.append(n / np.linalg.norm(n))
    vertices = np.array(vertex_rows, np.float32)
    normals = np.array(normal_rows, np.float32)
    v64, n64 = vertices.astype(np.float64), normals.astype(np.float64)
    r = envmap.reflect(v64 / np.linalg.norm(v64, axis=1, keepdims=True), n64)
    mesa = mesa_texgen(registry, vertices, normals)
    s, t = envmap.sphere_map_texgen(v64, n64)
    compare_texgen(mesa, np.stack([s, t], axis=1), r)
    radius = np.hypot(s - 0.5, t - 0.5)
    assert radius.max() > 0.4999  # the tightest tilt really is near the rim


# ------------------------------------------------------------- the renderer's texgen shader


def shader_texgen(
    vertices: np.ndarray, normals: np.ndarray, modelview: np.ndarray | None = None
) -> np.ndarray:
    """What the renderer's vertex shader for sphere-texgen (``envmap.vert`` with ``texgen``
    set, the scene's own shader text) gives object-space ``vertices`` and ``normals``
    ``(n, 3)`` float32 under ``modelview`` ``(4, 4)`` (identity if None) as its
    per-vertex ``(s, t)`` ``(n, 2)``: captured by transform feedback, nothing drawn."""
    n = len(vertices)
    modelview = np.eye(4) if modelview is None else modelview
    shader = GL.glCreateShader(GL.GL_VERTEX_SHADER)
    GL.glShaderSource(shader, expand_includes("envmap.vert"))
    GL.glCompileShader(shader)
    assert GL.glGetShaderiv(shader, GL.GL_COMPILE_STATUS), GL.glGetShaderInfoLog(shader)
    program = GL.glCreateProgram()
    GL.glAttachShader(program, shader)
    GL.glDeleteShader(shader)
    names = (ctypes.c_char_p * 1)(b"vertex_sphere_st")
    GL.glTransformFeedbackVaryings(
        program,
        1,
        ctypes.cast(names, ctypes.POINTER(ctypes.POINTER(GL.GLchar))),
        GL.GL_INTERLEAVED_ATTRIBS,
    )
    GL.glLinkProgram(program)
    assert GL.glGetProgramiv(program, GL.GL_LINK_STATUS), GL.glGetProgramInfoLog(program)
    vao = int(GL.glGenVertexArrays(1))
    vbo, captured = (int(b) for b in GL.glGenBuffers(2))
    try:
        GL.glUseProgram(program)
        for name, matrix in (("model", modelview), ("view", np.eye(4)), ("projection", np.eye(4))):
            GL.glUniformMatrix4fv(
                GL.glGetUniformLocation(program, name),
                1,
                GL.GL_TRUE,
                np.asarray(matrix, np.float32),
            )
        GL.glUniformMatrix3fv(
            GL.glGetUniformLocation(program, "normal_matrix"),
            1,
            GL.GL_TRUE,
            math3d.normal_matrix(modelview).astype(np.float32),
        )
        GL.glUniform1i(GL.glGetUniformLocation(program, "texgen"), 1)
        GL.glUniform1i(GL.glGetUniformLocation(program, "orthographic"), 0)
        GL.glUniform4f(GL.glGetUniformLocation(program, "clip_plane"), 0.0, 0.0, 0.0, 1.0)
        data = np.ascontiguousarray(np.concatenate([vertices, normals], axis=1), np.float32)
        GL.glBindVertexArray(vao)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, vbo)
        GL.glBufferData(GL.GL_ARRAY_BUFFER, data.nbytes, data, GL.GL_STATIC_DRAW)
        for location in (0, 1):
            GL.glEnableVertexAttribArray(location)
            GL.glVertexAttribPointer(
                location, 3, GL.GL_FLOAT, GL.GL_FALSE, 24, GL.GLvoidp(12 * location)
            )
        GL.glBindBuffer(GL.GL_TRANSFORM_FEEDBACK_BUFFER, captured)
        GL.glBufferData(GL.GL_TRANSFORM_FEEDBACK_BUFFER, 8 * n, None, GL.GL_STATIC_READ)
        GL.glBindBufferBase(GL.GL_TRANSFORM_FEEDBACK_BUFFER, 0, captured)
        GL.glEnable(GL.GL_RASTERIZER_DISCARD)
        GL.glBeginTransformFeedback(GL.GL_POINTS)
        GL.glDrawArrays(GL.GL_POINTS, 0, n)
        GL.glEndTransformFeedback()
        GL.glDisable(GL.GL_RASTERIZER_DISCARD)
        st = np.empty((n, 2), np.float32)
        GL.glGetBufferSubData(
            GL.GL_TRANSFORM_FEEDBACK_BUFFER, 0, st.nbytes, st.ctypes.data_as(ctypes.c_void_p)
        )
    finally:
        GL.glBindBufferBase(GL.GL_TRANSFORM_FEEDBACK_BUFFER, 0, 0)
        GL.glBindBuffer(GL.GL_TRANSFORM_FEEDBACK_BUFFER, 0)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, 0)
        GL.glBindVertexArray(0)
        GL.glUseProgram(0)
        GL.glDeleteVertexArrays(1, [vao])
        GL.glDeleteBuffers(2, [vbo, captured])
        GL.glDeleteProgram(program)
    return st.astype(np.float64)


def compare_with_mesa(mesa: np.ndarray, shader: np.ndarray, r_eye: np.ndarray) -> None:
    """The shader's formula is GL's, in float32 as Mesa's: the two agree to 1e-6 where
    the map is not steep (1 + rz >= 1e-2), to 2e-7 / sqrt(1 + rz) closer to the singular
    direction, where a float32 rounding of r moves (s, t) further (measured: most agree
    exactly, the worst of 3,580 by 1.2e-6 at 1 + rz ~ 1e-3)."""
    gap = 1 + r_eye[:, 2] / np.linalg.norm(r_eye, axis=1)
    tolerance = np.where(gap >= 1e-2, 1e-6, 2e-7 / np.sqrt(gap))
    error = np.abs(mesa - shader).max(axis=1)
    worst = int(np.argmax(error / tolerance))
    assert np.all(error <= tolerance), (
        f"{int((error > tolerance).sum())} of {len(error)} differ; worst "
        f"{error[worst]:.3g} at 1 + rz = {gap[worst]:.3g}: Mesa {mesa[worst]}, shader "
        f"{shader[worst]}"
    )


def test_texgen_shader_matches_mesa_texgen_over_many_directions(registry):
    rng = np.random.default_rng(38)
    vertices, normals = texgen_cases(rng)
    # Besides the structured cases, 3,000 random view rays against random normals.
    u = random_directions(rng, 3000)
    vertices = np.concatenate([vertices, u * rng.uniform(0.5, 60, (3000, 1))])
    normals = np.concatenate([normals, random_directions(rng, 3000)]).astype(np.float32)
    vertices = vertices.astype(np.float32)
    v64, n64 = vertices.astype(np.float64), normals.astype(np.float64)
    r = envmap.reflect(v64 / np.linalg.norm(v64, axis=1, keepdims=True), n64)
    regular = 1 + r[:, 2] >= 1e-6  # Mesa's NaN at r = (0, 0, -1) is tested apart, below
    assert regular.sum() >= 3000
    mesa = mesa_texgen(registry, vertices[regular], normals[regular], normalize=True)
    shader = shader_texgen(vertices[regular], normals[regular])
    compare_with_mesa(mesa, shader, r[regular])


def test_texgen_shader_matches_mesa_texgen_under_a_modelview(registry):
    vertices, normals, modelview, _, _, r, regular = modelview_case(39)
    mesa = mesa_texgen(registry, vertices[regular], normals[regular], modelview, normalize=True)
    shader = shader_texgen(vertices[regular], normals[regular], modelview)
    compare_with_mesa(mesa, shader, r[regular])


def test_texgen_shader_stays_finite_where_mesa_texgen_gives_nan(registry):
    # r = (0, 0, -1): a vertex straight ahead, its normal edge-on; a vertex at the eye;
    # a zero normal. Mesa gives NaN for the first two (DESIGN.md); the shader gives
    # numpy's documented values.
    vertices = np.array([[0.0, 0.0, -3.0], [0.0, 0.0, 0.0], [0.5, -0.25, -2.0]], np.float32)
    normals = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]], np.float32)
    mesa = mesa_texgen(registry, vertices[:2], normals[:2])
    assert np.isnan(mesa).any(axis=1).all(), f"Mesa's texgen is finite here now: {mesa}"
    shader = shader_texgen(vertices, normals)
    assert np.isfinite(shader).all()
    s, t = envmap.sphere_map_texgen(vertices.astype(np.float64), normals.astype(np.float64))
    assert np.allclose(shader, np.stack([s, t], axis=1), atol=1e-6), shader
    assert np.allclose(shader[:2], [[1.0, 0.5], [0.5, 0.5]])


# ---------------------------------------------------------------------------- cube sampler

CUBE_VERTEX = """#version 330
void main() {
    // One triangle covering the viewport.
    gl_Position = vec4(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0, 0.0, 1.0);
}
"""
CUBE_FRAGMENT = """#version 330
uniform samplerCube cube;
uniform sampler2D directions;
out vec4 colour;
void main() {
    colour = texture(cube, texelFetch(directions, ivec2(gl_FragCoord.xy), 0).xyz);
}
"""
CUBE_UNIT, DIRECTION_UNIT = 1, 2


def _program() -> int:
    program = GL.glCreateProgram()
    for source, kind in (
        (CUBE_VERTEX, GL.GL_VERTEX_SHADER),
        (CUBE_FRAGMENT, GL.GL_FRAGMENT_SHADER),
    ):
        shader = GL.glCreateShader(kind)
        GL.glShaderSource(shader, source)
        GL.glCompileShader(shader)
        ok = GL.glGetShaderiv(shader, GL.GL_COMPILE_STATUS)
        log = GL.glGetShaderInfoLog(shader)
        GL.glAttachShader(program, shader)
        GL.glDeleteShader(shader)
        assert ok, log
    GL.glLinkProgram(program)
    assert GL.glGetProgramiv(program, GL.GL_LINK_STATUS), GL.glGetProgramInfoLog(program)
    return program


def _float_texture(target: int, width: int, height: int, data: np.ndarray | None) -> None:
    GL.glTexImage2D(target, 0, GL.GL_RGBA32F, width, height, 0, GL.GL_RGBA, GL.GL_FLOAT, data)


def mesa_cube_texels(directions: np.ndarray, size: int, seamless: bool = False) -> np.ndarray:
    """(face, column, row) ``(n, 3)`` int that Mesa's sampler picks for ``directions``
    ``(n, 3)`` float32 on a ``size``-texel GL_NEAREST cube map, with
    ``GL_TEXTURE_CUBE_MAP_SEAMLESS`` on or off (restored afterwards).

    Texel (row ``i``, column ``j``) of face ``k`` stores ``(k, j, i, 1)`` in RGBA32F,
    uploaded with glTexImage2D, so row ``i`` of the data is at ``t`` in
    ``[i/size, (i+1)/size)``.
    """
    n = len(directions)
    width = 64
    height = -(-n // width)
    padded = np.zeros((height * width, 4), np.float32)
    padded[:n, :3] = directions
    previous_viewport = GL.glGetIntegerv(GL.GL_VIEWPORT)
    was_seamless = bool(GL.glIsEnabled(GL.GL_TEXTURE_CUBE_MAP_SEAMLESS))
    (GL.glEnable if seamless else GL.glDisable)(GL.GL_TEXTURE_CUBE_MAP_SEAMLESS)
    cube, direction_texture, output = (int(t) for t in GL.glGenTextures(3))
    framebuffer = int(GL.glGenFramebuffers(1))
    program = _program()
    try:
        GL.glActiveTexture(GL.GL_TEXTURE0 + CUBE_UNIT)
        GL.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, cube)
        columns, rows = np.meshgrid(np.arange(size), np.arange(size))
        for face in range(6):
            texels = np.stack(
                [np.full_like(rows, face), columns, rows, np.ones_like(rows)], axis=-1
            ).astype(np.float32)
            _float_texture(GL.GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, size, size, texels)
        for name, value in (
            (GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST),
            (GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST),
            (GL.GL_TEXTURE_WRAP_S, GL.GL_CLAMP_TO_EDGE),
            (GL.GL_TEXTURE_WRAP_T, GL.GL_CLAMP_TO_EDGE),
            (GL.GL_TEXTURE_MAX_LEVEL, 0),
        ):
            GL.glTexParameteri(GL.GL_TEXTURE_CUBE_MAP, name, value)
        GL.glActiveTexture(GL.GL_TEXTURE0 + DIRECTION_UNIT)
        GL.glBindTexture(GL.GL_TEXTURE_2D, direction_texture)
        _float_texture(GL.GL_TEXTURE_2D, width, height, padded.reshape(height, width, 4))
        GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
        GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glBindTexture(GL.GL_TEXTURE_2D, output)
        _float_texture(GL.GL_TEXTURE_2D, width, height, None)
        GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
        GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, framebuffer)
        GL.glFramebufferTexture2D(
            GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, GL.GL_TEXTURE_2D, output, 0
        )
        assert GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER) == GL.GL_FRAMEBUFFER_COMPLETE
        GL.glViewport(0, 0, width, height)
        GL.glUseProgram(program)
        GL.glUniform1i(GL.glGetUniformLocation(program, "cube"), CUBE_UNIT)
        GL.glUniform1i(GL.glGetUniformLocation(program, "directions"), DIRECTION_UNIT)
        GL.glDrawArrays(GL.GL_TRIANGLES, 0, 3)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 4)
        pixels = GL.glReadPixels(0, 0, width, height, GL.GL_RGBA, GL.GL_FLOAT)
        result = np.frombuffer(pixels, np.float32).reshape(-1, 4)[:n]
    finally:
        GL.glUseProgram(0)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)
        GL.glDeleteFramebuffers(1, [framebuffer])
        GL.glDeleteProgram(program)
        GL.glActiveTexture(GL.GL_TEXTURE0 + CUBE_UNIT)
        GL.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, 0)
        GL.glActiveTexture(GL.GL_TEXTURE0 + DIRECTION_UNIT)
        GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
        GL.glDeleteTextures([cube, direction_texture, output])
        GL.glViewport(*(int(v) for v in previous_viewport))
        (GL.glEnable if was_seamless else GL.glDisable)(GL.GL_TEXTURE_CUBE_MAP_SEAMLESS)
    assert np.all(result[:, 3] == 1), "a sample missed the cube's texels"
    assert np.all(result[:, :3] == np.round(result[:, :3])), "texels must be integers"
    return result[:, :3].astype(np.int64)


def numpy_cube_texels(directions: np.ndarray, size: int) -> tuple[np.ndarray, ...]:
    """numpy's (face, column, row) and the texel-space coordinates they come from."""
    face, s, t = envmap.cube_map(directions.astype(np.float64))
    u, v = s * size, t * size
    column = np.minimum(np.floor(u), size - 1).astype(np.int64)  # s = 1 clamps to the edge
    row = np.minimum(np.floor(v), size - 1).astype(np.int64)
    return face, column, row, u, v


def assert_same_texels(
    mesa: np.ndarray, directions: np.ndarray, size: int, min_exact_fraction: float
) -> None:
    """Faces must agree exactly. Texel indices too, except within 1e-4 texel of a texel
    boundary, where Mesa's float32 arithmetic may land on the neighbour."""
    face, column, row, u, v = numpy_cube_texels(directions, size)
    bad_face = np.nonzero(mesa[:, 0] != face)[0]
    assert len(bad_face) == 0, (
        f"{len(bad_face)} face mismatches, e.g. r = {directions[bad_face[:3]].tolist()}: "
        f"Mesa {mesa[bad_face[:3], 0].tolist()}, numpy {face[bad_face[:3]].tolist()}"
    )
    margin = 1e-4

    def allowed(index, coordinate):
        low = np.clip(np.floor(coordinate - margin), 0, size - 1)
        high = np.clip(np.floor(coordinate + margin), 0, size - 1)
        return (index >= low) & (index <= high)

    exact = (mesa[:, 1] == column) & (mesa[:, 2] == row)
    tolerated = allowed(mesa[:, 1], u) & allowed(mesa[:, 2], v)
    bad = np.nonzero(~(exact | tolerated))[0]
    assert len(bad) == 0, (
        f"{len(bad)} texel mismatches, e.g. r = {directions[bad[:3]].tolist()}: Mesa "
        f"{mesa[bad[:3]].tolist()}, numpy {np.stack([face, column, row], 1)[bad[:3]].tolist()}"
    )
    assert exact.mean() >= min_exact_fraction, f"only {exact.mean():.3f} matched exactly"


def test_cube_map_matches_mesa_sampler_on_random_and_near_edge_directions():
    size = 32
    rng = np.random.default_rng(30)
    random = random_directions(rng, 3000) * rng.uniform(0.01, 100, (3000, 1))
    # Just inside each face's edges and corners: s or t a hair from 0 or 1.
    count = 1500
    faces = rng.integers(0, 6, count)
    s = rng.uniform(0, 1, count)
    t = rng.choice([1e-5, 1e-3, 1 - 1e-3, 1 - 1e-5], count)
    swap = rng.random(count) < 0.5
    s, t = np.where(swap, t, s), np.where(swap, s, t)
    near_edges = envmap.cube_face_direction(faces, s, t)
    # On texel boundaries of each face (float32 rounding decides the side).
    boundary = envmap.cube_face_direction(
        rng.integers(0, 6, 500), rng.integers(0, size + 1, 500) / size, rng.uniform(0, 1, 500)
    )
    directions = np.concatenate([random, near_edges, boundary]).astype(np.float32)
    mesa = mesa_cube_texels(directions, size)
    assert_same_texels(mesa, directions, size, min_exact_fraction=0.9)
    # The random directions themselves sit off texel boundaries: all exact.
    face, column, row, _, _ = numpy_cube_texels(directions[:3000], size)
    assert np.array_equal(mesa[:3000], np.stack([face, column, row], axis=1))


def tie_directions(rng) -> np.ndarray:
    """Exact ties: edges, corners, axes, signed zeros, r = 0, and random ties."""
    signs = np.array([[sx, sy, sz] for sx in (1, -1) for sy in (1, -1) for sz in (1, -1)], float)
    corners = np.concatenate([signs, 2.5 * signs])
    edges = []
    for third in (0.0, -0.0, 0.3, -0.7, 0.999):
        for a, b in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
            edges += [[a, b, third], [a, third, b], [third, a, b]]
    axes = np.concatenate([np.eye(3), -np.eye(3)])
    signed_zero_axes = np.array(
        [[1, -0.0, 0.0], [-0.0, -1, -0.0], [0.0, -0.0, -1], [-1, -0.0, -0.0]]
    )
    zeros = signs * 0.0  # all eight sign patterns of r = 0
    # Random ties between two or three components, random signs and order.
    magnitude = rng.uniform(0.01, 10, (400, 1))
    other = rng.uniform(-1, 1, (400, 1)) * magnitude
    ties = np.concatenate([magnitude, magnitude, other], axis=1)
    ties[:100, 2] = magnitude[:100, 0]  # three-way
    ties *= rng.choice([-1.0, 1.0], ties.shape)
    order = np.argsort(rng.random(ties.shape), axis=1)
    ties = np.take_along_axis(ties, order, axis=1)
    return np.concatenate([corners, edges, axes, signed_zero_axes, zeros, ties])


@pytest.mark.parametrize("seamless", [False, True], ids=["seams", "seamless"])
def test_cube_map_matches_mesa_sampler_at_ties_edges_corners_and_zero(seamless):
    # What Mesa (22.3 llvmpipe) does where the spec does not say: on ties Z wins over Y
    # and Y over X; the sign bit of the major component picks the face (r = (0, 0, -0.0)
    # goes to -Z); r = 0 samples the centre of +Z (or -Z when rz is -0.0). numpy's
    # cube_map documents the same rule, so the two agree exactly here as well.
    # (Subnormal components are left out: llvmpipe flushes them to zero, numpy keeps
    # their direction.) With GL_NEAREST, GL_TEXTURE_CUBE_MAP_SEAMLESS changes nothing.
    size = 16
    rng = np.random.default_rng(31)
    directions = tie_directions(rng).astype(np.float32)
    mesa = mesa_cube_texels(directions, size, seamless)
    assert_same_texels(mesa, directions, size, min_exact_fraction=0.95)
    # Whatever rule a sampler uses, at a tie it must name one of the tied faces, and the
    # texel on that face that touches the shared edge: the one numpy finds when the
    # direction is nudged a hair into that face.
    mags = np.abs(directions.astype(np.float64))
    nonzero = mags.max(axis=1) > 0
    for r, (face, column, row) in zip(
        directions[nonzero].astype(np.float64), mesa[nonzero], strict=True
    ):
        axis = face // 2
        assert abs(r[axis]) == np.abs(r).max(), f"Mesa's face {face} is not tied for {r}"
        nudged = r.copy()
        nudged[axis] += (-1 if face % 2 else 1) * 1e-9 * abs(r[axis])
        f2, c2, r2, _, _ = numpy_cube_texels(nudged[None], size)
        assert (int(f2[0]), int(c2[0]), int(r2[0])) == (face, column, row), r


@pytest.mark.parametrize("size", [1, 2, 5])
def test_cube_map_matches_mesa_sampler_on_tiny_and_odd_sizes(size):
    rng = np.random.default_rng(32 + size)
    directions = np.concatenate([random_directions(rng, 500), tie_directions(rng)[:200]])
    directions = directions.astype(np.float32)
    mesa = mesa_cube_texels(directions, size)
    assert_same_texels(mesa, directions, size, min_exact_fraction=0.95)
