"""What every lab's given drawing shares, on the trusted side: the kit's shaders (and the
student's GLSL linked into them), meshes, pictures, textures read back, and
:class:`LabBase`, the session each lab's ``trusted.SESSION`` extends with its own scene
(the robot, the cone, the sphere), its numbers taken from its variant (:mod:`.variants`).

A session lives in the executor's GL context (:mod:`.call_executor`); the student's file
reaches its drawing calls (``lab.draw_scene``, ``lab.draw_cone_shader``, ...) only as
messages that the executor validates. Texture units: the given drawing binds object
textures on unit 0 and leaves unit 0 active; the labs keep their environment textures
on unit 1 (the sphere-map lab's texgen cone is textured from the variant's unit).
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from mirrorlab import math3d
from mirrorlab.data import model_file, texture_file
from mirrorlab.labs.trusted import legacy
from mirrorlab.labs.trusted.compat_glsl import TRANSLATED_STATE, translate_compat_glsl
from mirrorlab.labs.trusted.glsl_source import GlslRefused, prepare
from mirrorlab.labs.trusted.variants import Variant

ENV_UNIT = 1
STUDENT_MARK = "// STUDENT CODE"
PICTURES = ("metal", "launch", "wall")
"""The pictures ``lab.load_picture_texture`` may load."""


class LabSetupError(RuntimeError):
    """The lab could not do what was asked (a bad argument, a bad GLSL string); one line."""


class StudentShaderError(LabSetupError):
    """The student's GLSL did not compile: ``variable`` names the Python string, ``line``
    the line inside it (1-based, or 0 when unknown)."""

    def __init__(self, variable: str, line: int, message: str, refused: bool = False) -> None:
        self.variable, self.line, self.detail, self.refused = variable, line, message, refused
        where = f"{variable} line {line}" if line else variable
        verb = "is refused" if refused else "did not compile"
        super().__init__(f"GLSL in {where} {verb}: {message}")


def lazy_gl():
    from mirrorlab.gl.opengl import GL

    return GL


def compile_program(
    vertex: str, fragment: str, student: str | None = None, variable: str = ""
) -> int:
    """A linked program from package shader files (``#include`` expanded). ``student``
    GLSL is compiled alone, as a shader object of its own (its own preprocessor: no macro
    of it reaches the kit's code), of the stage whose file has the :data:`STUDENT_MARK`
    line, and linked to that file's ``main``, which calls it through the prototypes after
    the mark; it may declare no uniform of its own (the kit's inputs reach it as
    arguments). The student's GLSL has its compatibility built-ins translated
    (:mod:`.compat_glsl`); so has a kit file written for immediate mode when the context
    has no compatibility profile (:mod:`.legacy`). Returns the GL program name;
    StudentShaderError for the student's GLSL, LabSetupError for the kit's."""
    from mirrorlab.gl.resources import expand_includes

    GL = lazy_gl()
    shaders, student_shaders = [], []
    try:
        for name, kind in ((vertex, GL.GL_VERTEX_SHADER), (fragment, GL.GL_FRAGMENT_SHADER)):
            stage = "vertex" if kind == GL.GL_VERTEX_SHADER else "fragment"
            source = expand_includes(name)
            if legacy.emulated() is not None:
                source = translate_compat_glsl(source, stage)
            shaders.append(_compiled(kind, source, f"kit shader {name}", variable))
            if student is not None and STUDENT_MARK in source:
                student_shaders.append(student_shader(kind, source, student, variable))
        program = _linked(
            [*shaders, *student_shaders],
            f"{vertex}+{fragment}",
            variable if student is not None else "",
        )
        if student_shaders:
            try:
                _only_arguments(expand_includes(fragment), student_shaders, variable)
            except StudentShaderError:
                GL.glDeleteProgram(program)
                raise
        return program
    finally:
        for shader in [*shaders, *student_shaders]:
            GL.glDeleteShader(shader)


def student_interface(kit_source: str) -> tuple[str, list[tuple[str, str, str]]]:
    """What a kit shader file offers the student's GLSL: its ``#version`` line ('' when it
    has none) and the prototypes after its :data:`STUDENT_MARK` line, ``(result type,
    name, parameters)`` each, the interface the student's functions are linked through."""
    before, _, after = kit_source.partition(STUDENT_MARK)
    version = next(
        (line for line in before.splitlines() if line.strip().startswith("#version")), ""
    )
    return version, PROTOTYPE.findall(after.split("\n\n")[0])


def student_shader(kind: int, kit_source: str, glsl: str, variable: str) -> int:
    """The student's GLSL ``glsl`` (of ``variable``) compiled as a shader object of its own,
    of stage ``kind``: the kit file's ``#version`` line, then the text preprocessed and
    checked here (:func:`.glsl_source.prepare`: no directive and no macro reaches the
    driver, no ``ml_`` name and no declaration outside the functions) with its
    compatibility built-ins translated, as source string 1 (its lines counted from 1).
    StudentShaderError when it is refused or does not compile."""
    stage = "vertex" if kind == lazy_gl().GL_VERTEX_SHADER else "fragment"
    version, _ = student_interface(kit_source)
    try:
        prepared = prepare(glsl, version or "#version 330 core")
    except GlslRefused as exc:
        raise StudentShaderError(variable, exc.line, exc.message, refused=True) from None
    source = f"{version}\n#line 1 1\n{translate_compat_glsl(prepared, stage)}\n"
    return _compiled(kind, source, "", variable)


def _text(log: bytes | str) -> str:
    return (log.decode(errors="replace") if isinstance(log, bytes) else str(log)).strip()


def _compiled(kind: int, source: str, what: str, variable: str) -> int:
    """A compiled shader object; ``what`` '' for the student's GLSL."""
    GL = lazy_gl()
    shader = GL.glCreateShader(kind)
    GL.glShaderSource(shader, source)
    GL.glCompileShader(shader)
    if not GL.glGetShaderiv(shader, GL.GL_COMPILE_STATUS):
        log = _text(GL.glGetShaderInfoLog(shader))
        GL.glDeleteShader(shader)
        if not what:
            raise StudentShaderError(variable, *_student_log_line(log))
        raise LabSetupError(f"{what} did not compile: {log}")
    return int(shader)


def _linked(shaders: list[int], what: str, variable: str) -> int:
    GL = lazy_gl()
    program = GL.glCreateProgram()
    for shader in shaders:
        GL.glAttachShader(program, shader)
    GL.glLinkProgram(program)
    for shader in shaders:
        GL.glDetachShader(program, shader)
    if not GL.glGetProgramiv(program, GL.GL_LINK_STATUS):
        log = _text(GL.glGetProgramInfoLog(program))
        GL.glDeleteProgram(program)
        if variable:
            first = log.splitlines()[0] if log else "link failed"
            raise StudentShaderError(variable, 0, f"it does not link to the lab's shader ({first})")
        raise LabSetupError(f"kit program {what} did not link: {log}")
    return int(program)


PROTOTYPE = re.compile(r"^\s*(\w+)\s+(\w+)\s*\(([^)]*)\)\s*;", re.MULTILINE)
STUB_ARGUMENTS = {
    "float": "gl_FragCoord.x",
    "int": "int(gl_FragCoord.x)",
    "vec2": "gl_FragCoord.xy",
    "vec3": "gl_FragCoord.xyz",
    "vec4": "gl_FragCoord",
}
STUB_RESULTS = {
    "float": "{}",
    "int": "float({})",
    "vec2": "dot({}, vec2(1.0))",
    "vec3": "dot({}, vec3(1.0))",
    "vec4": "dot({}, vec4(1.0))",
}


def _only_arguments(kit_source: str, student_shaders: list[int], variable: str) -> None:
    """StudentShaderError when the student's functions read a uniform (the kit's own,
    such as its check mode or samplers, or one of theirs that nothing sets; GL's built-in
    state such as ``gl_ModelViewMatrix`` is allowed): they are
    linked to a main of their own that calls each through the kit's prototypes and
    declares no uniform, so every uniform active there is theirs."""
    GL = lazy_gl()
    version_line, prototypes = student_interface(kit_source)
    calls = []
    for result, name, params in prototypes:
        args = [STUB_ARGUMENTS[p.split()[-2]] for p in params.split(",") if p.strip()]
        calls.append(STUB_RESULTS[result].format(f"{name}({', '.join(args)})"))
    declared = "".join(f"{r} {n}({p});\n" for r, n, p in prototypes)
    stub = (
        f"{version_line}\n{declared}out vec4 ml_stub_out;\nvoid main() {{\n"
        f"    ml_stub_out = vec4({' + '.join(calls) or '0.0'});\n}}\n"
    )
    main = _compiled(GL.GL_FRAGMENT_SHADER, stub, "the kit's stub", variable)
    program = GL.glCreateProgram()
    try:
        for shader in [main, *student_shaders]:
            GL.glAttachShader(program, shader)
        GL.glLinkProgram(program)
        if not GL.glGetProgramiv(program, GL.GL_LINK_STATUS):
            log = _text(GL.glGetProgramInfoLog(program))
            raise StudentShaderError(
                variable,
                0,
                f"it does not link on its own ({(log.splitlines() or ['link failed'])[0]})",
            )
        names = []
        for index in range(int(GL.glGetProgramiv(program, GL.GL_ACTIVE_UNIFORMS))):
            name, _, kind = GL.glGetActiveUniform(program, index)
            name = _text(name)
            # GL's own state (gl_ModelViewMatrix, or its translation for a core context)
            # is not the kit's: the same for every draw; only the translation's own
            # names and types (the student's text may not name ml_ itself)
            if not name.startswith("gl_") and TRANSLATED_STATE.get(name) != int(kind):
                names.append(name)
        if names or GL.glGetProgramiv(program, GL.GL_ACTIVE_UNIFORM_BLOCKS):
            shown = ", ".join(names) or "a uniform block"
            raise StudentShaderError(
                variable,
                0,
                f"it reads uniforms ({shown[:80]}); the "
                f"lab's functions take what they need as arguments",
            )
    finally:
        GL.glDeleteProgram(program)
        GL.glDeleteShader(main)


def _student_log_line(log: str) -> tuple[int, str]:
    """(line in the student's string, first message) from a Mesa compile log whose student
    part was compiled as source string 1."""
    for line in log.splitlines():
        match = re.match(r"\s*(\d+):(\d+)\((\d+)\):\s*(.*)", line)
        if match and match.group(1) == "1":
            return int(match.group(2)), match.group(4)
    return 0, (log.splitlines()[0] if log else "compile failed")


def uniform(program: int, name: str) -> int:
    return int(lazy_gl().glGetUniformLocation(program, name))


def load_matrix(mode: int, matrix: np.ndarray) -> None:
    FF = legacy.gl()
    FF.glMatrixMode(mode)
    FF.glLoadMatrixd(np.ascontiguousarray(np.asarray(matrix, dtype=np.float64).T))


def current_matrices() -> tuple[np.ndarray, np.ndarray]:
    """The fixed-function (projection, modelview) matrices now, ``(4, 4)`` each, row-major
    (the emulated ones on a core context: :mod:`.legacy`)."""
    return legacy.current_matrices()


@contextmanager
def modelview_times(model: np.ndarray) -> Iterator[None]:
    """The modelview matrix times ``model`` (row-major ``(4, 4)``) while the kit draws,
    the file's own again after, with the modelview matrix current: loaded, never pushed
    (the file's stack may be full). The product is summed in float32 in the order GL's
    own glMultMatrix sums it (:func:`.legacy.multiply`), so it is the matrix a push and a
    glMultMatrix would have made."""
    GL = lazy_gl()
    FF = legacy.gl()
    FF.glMatrixMode(GL.GL_MODELVIEW)
    _, saved = current_matrices()
    top = saved.astype(np.float32)
    product = legacy.multiply(top, np.asarray(model, dtype=np.float64).astype(np.float32))
    FF.glLoadMatrixf(np.ascontiguousarray(product.T))
    try:
        yield
    finally:
        FF.glMatrixMode(GL.GL_MODELVIEW)
        FF.glLoadMatrixf(np.ascontiguousarray(top.T))


RASTER_CAPS = (
    "GL_BLEND",
    "GL_SCISSOR_TEST",
    "GL_STENCIL_TEST",
    "GL_CULL_FACE",
    "GL_POLYGON_OFFSET_FILL",
)
"""Switches that change which of a draw's fragments land and how: off for the kit's draws."""
LEGACY_CAPS = ("GL_ALPHA_TEST", "GL_FOG", "GL_LIGHTING")
"""The fixed pipeline's switches that change what a draw writes: off for the kit's draws
(the emulation's own on a core context)."""


@contextmanager
def kit_state() -> Iterator[None]:
    """The raster state the kit's draws depend on, set for them whatever the file left
    (blending, scissor, stencil, culling, polygon offset and mode, the alpha test, fog and
    lighting off; depth test on with GL_LESS, depth and colour writes on), and the file's
    own back after. What the kit's drawing is documented to use or leave (the matrices, the
    viewport, unit 0 with the object textures bound there) is not touched here."""
    GL = lazy_gl()
    FF = legacy.gl()
    caps = {
        name: bool(GL.glIsEnabled(getattr(GL, name))) for name in (*RASTER_CAPS, "GL_DEPTH_TEST")
    }
    legacy_caps = {name: bool(FF.glIsEnabled(getattr(GL, name))) for name in LEGACY_CAPS}
    colour_mask = [
        bool(v) for v in np.asarray(GL.glGetBooleanv(GL.GL_COLOR_WRITEMASK)).reshape(-1)[:4]
    ]
    depth_mask = bool(np.asarray(GL.glGetBooleanv(GL.GL_DEPTH_WRITEMASK)).reshape(-1)[0])
    depth_func = int(np.asarray(GL.glGetIntegerv(GL.GL_DEPTH_FUNC)).reshape(-1)[0])
    polygon_modes = [int(v) for v in np.asarray(GL.glGetIntegerv(GL.GL_POLYGON_MODE)).reshape(-1)]
    for name in RASTER_CAPS:
        GL.glDisable(getattr(GL, name))
    for name in LEGACY_CAPS:
        FF.glDisable(getattr(GL, name))
    GL.glEnable(GL.GL_DEPTH_TEST)
    GL.glColorMask(True, True, True, True)
    GL.glDepthMask(True)
    GL.glDepthFunc(GL.GL_LESS)
    GL.glPolygonMode(GL.GL_FRONT_AND_BACK, GL.GL_FILL)
    try:
        yield
    finally:
        for name, on in caps.items():
            (GL.glEnable if on else GL.glDisable)(getattr(GL, name))
        for name, on in legacy_caps.items():
            (FF.glEnable if on else FF.glDisable)(getattr(GL, name))
        GL.glColorMask(*colour_mask)
        GL.glDepthMask(depth_mask)
        GL.glDepthFunc(depth_func)
        if legacy.emulated() is None and len(polygon_modes) > 1:  # each face its own
            GL.glPolygonMode(GL.GL_FRONT, polygon_modes[0])
            GL.glPolygonMode(GL.GL_BACK, polygon_modes[1])
        else:
            FF.glPolygonMode(GL.GL_FRONT_AND_BACK, polygon_modes[0])


class Mesh:
    """One mesh file in a vertex buffer, drawn with generic attributes 0 (position),
    1 (normal) and 2 (texture coordinate), which the compatibility profile's
    ``gl_Vertex`` aliases too."""

    def __init__(self, name: str) -> None:
        from mirrorlab.gl.resources import upload_mesh

        vertices, indices = mesh_arrays(name)
        self.count = int(indices.size)
        # the session's meshes live as long as its process: no registry, nothing to free
        self.vao, self.vbo, self.ebo = upload_mesh(vertices, indices)

    def draw(self) -> None:
        GL = lazy_gl()
        GL.glBindVertexArray(self.vao)
        GL.glDrawElements(GL.GL_TRIANGLES, self.count, GL.GL_UNSIGNED_INT, None)
        GL.glBindVertexArray(0)


@lru_cache(maxsize=32)
def mesh_arrays(name: str) -> tuple[np.ndarray, np.ndarray]:
    """The shipped mesh ``name`` as interleaved float32 vertices and uint32 indices (read
    once a process, through the asset cache: :mod:`.assets`)."""
    from mirrorlab.labs.trusted.assets import cached_arrays
    from mirrorlab.scene import mesh

    def read() -> dict[str, np.ndarray]:
        data = mesh.load_mesh(model_file(name))
        return {
            "vertices": np.ascontiguousarray(data.interleaved(), dtype=np.float32),
            "indices": np.ascontiguousarray(data.indices.reshape(-1), dtype=np.uint32),
        }

    sources = [model_file(name), Path(mesh.__file__)]
    arrays = cached_arrays("mesh", name, sources, ("trimesh", "numpy"), read)
    for array in arrays.values():
        array.flags.writeable = False
    return arrays["vertices"], arrays["indices"]


@lru_cache(maxsize=8)
def picture(name: str) -> np.ndarray:
    """``textures/<name>.png`` as ``(h, w, 3)`` uint8, row 0 at the top (read once a
    process, through the asset cache: :mod:`.assets`)."""
    from mirrorlab.labs.trusted.assets import cached_arrays
    from mirrorlab.scene import backgrounds

    def read() -> dict[str, np.ndarray]:
        return {"pixels": backgrounds.load_picture(texture_file(name))}

    sources = [texture_file(name), Path(backgrounds.__file__)]
    pixels = cached_arrays("picture", name, sources, ("pillow",), read)["pixels"]
    pixels.flags.writeable = False
    return pixels


def mipmap_levels(image: np.ndarray) -> list[np.ndarray] | None:
    """The mipmap chain of ``image`` (``(n, n, 3)`` uint8, ``n`` a power of two; rows in
    GL's order): level 0 (``image``) to the 1 x 1 level, each texel the mean of the 2 x 2
    texels below it, rounded as llvmpipe's ``glGenerateMipmap`` rounds it (each row's pair,
    then the two rows; texel for texel the same on the shipped pictures). None for another
    shape, which GL then mipmaps itself."""
    size = image.shape[0]
    if image.ndim != 3 or image.shape[1] != size or size < 1 or size & (size - 1):
        return None
    levels = [image]
    level: np.ndarray = image.astype(np.uint16)
    while level.shape[0] > 1:
        top = (level[0::2, 0::2] + level[0::2, 1::2] + 1) >> 1
        bottom = (level[1::2, 0::2] + level[1::2, 1::2] + 1) >> 1
        level = (top + bottom + 1) >> 1
        levels.append(level.astype(np.uint8))
    return levels


@lru_cache(maxsize=8)
def picture_levels(name: str) -> tuple[np.ndarray, ...]:
    """The picture ``name``'s mipmap chain in GL's row order (:func:`mipmap_levels`), or
    level 0 alone where GL must make the others; made once a process."""
    image = np.ascontiguousarray(picture(name)[::-1])
    levels = tuple(mipmap_levels(image) or [image])
    for level in levels:
        level.flags.writeable = False
    return levels


def upload_picture(texture_id: int, name: str) -> None:
    """Fill GL texture ``texture_id`` (bound on the active unit) with the picture ``name``
    (one of :data:`PICTURES`): mipmapped, repeating, trilinear. The levels are uploaded
    as :func:`picture_levels` makes them: ``glGenerateMipmap`` would build a shader in each
    new context, on llvmpipe a large share of a check's time."""
    GL = lazy_gl()
    levels = picture_levels(name)
    GL.glBindTexture(GL.GL_TEXTURE_2D, int(texture_id))
    GL.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 1)
    for number, level in enumerate(levels):
        GL.glTexImage2D(
            GL.GL_TEXTURE_2D,
            number,
            GL.GL_RGB8,
            level.shape[1],
            level.shape[0],
            0,
            GL.GL_RGB,
            GL.GL_UNSIGNED_BYTE,
            level,
        )
    if len(levels) == 1:
        GL.glGenerateMipmap(GL.GL_TEXTURE_2D)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_LINEAR_MIPMAP_LINEAR)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_LINEAR)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_S, GL.GL_REPEAT)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_T, GL.GL_REPEAT)


def read_level(target: int, level: int) -> np.ndarray:
    """Level ``level`` of image ``target`` (GL_TEXTURE_2D or a cube face) of the texture
    bound on the active unit, ``(h, w, 3)`` uint8 with row 0 at the top, ``(0, 0, 3)``
    when it has no storage: a colour format as its red, green and blue (a luminance one as
    GL reads it back), a depth format as grey (depth 0 to 1, black to white), whatever
    the file's copies and uploads made it."""
    GL = lazy_gl()
    width = int(GL.glGetTexLevelParameteriv(target, level, GL.GL_TEXTURE_WIDTH))
    height = int(GL.glGetTexLevelParameteriv(target, level, GL.GL_TEXTURE_HEIGHT))
    if width <= 0 or height <= 0:
        return np.zeros((0, 0, 3), dtype=np.uint8)
    GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
    if int(GL.glGetTexLevelParameteriv(target, level, GL.GL_TEXTURE_DEPTH_SIZE)):
        depth = np.zeros((height, width), dtype=np.float32)
        GL.glGetTexImage(target, level, GL.GL_DEPTH_COMPONENT, GL.GL_FLOAT, depth)
        grey = np.round(np.clip(depth, 0.0, 1.0) * 255).astype(np.uint8)
        image = np.repeat(grey[..., None], 3, axis=-1)
    else:
        image = np.zeros((height, width, 3), dtype=np.uint8)
        GL.glGetTexImage(target, level, GL.GL_RGB, GL.GL_UNSIGNED_BYTE, image)
    GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 4)
    return np.ascontiguousarray(image[::-1])


def read_texture_2d(texture_id: int, level: int = 0) -> np.ndarray:
    """Level ``level`` of 2D texture ``texture_id`` as ``(h, w, 3)`` uint8, row 0 at the
    top; (0, 0, 3) when it has no storage (:func:`read_level`). Keeps the active unit's
    binding."""
    GL = lazy_gl()
    previous = int(GL.glGetIntegerv(GL.GL_TEXTURE_BINDING_2D))
    GL.glBindTexture(GL.GL_TEXTURE_2D, int(texture_id))
    try:
        return read_level(GL.GL_TEXTURE_2D, level)
    finally:
        GL.glBindTexture(GL.GL_TEXTURE_2D, previous)


def read_cube_faces(texture: int) -> np.ndarray | None:
    """The six level-0 faces of cube map ``texture``, ``(6, n, n, 3)`` uint8 (row 0 at
    ``t = 1``; :func:`read_level`), or None when they are not all the same square size."""
    GL = lazy_gl()
    previous = int(GL.glGetIntegerv(GL.GL_TEXTURE_BINDING_CUBE_MAP))
    GL.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, texture)
    faces: list[np.ndarray] = []
    try:
        for face in range(6):
            found = read_level(GL.GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0)
            width = found.shape[0]
            if width == 0 or found.shape[1] != width or (faces and faces[0].shape[0] != width):
                return None
            faces.append(found)
    finally:
        GL.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, previous)
    return np.stack(faces)


def texture_parameters(texture_id: int, target: int | None = None) -> dict[str, int]:
    """The sampling parameters of ``texture_id`` (a 2D texture unless ``target`` says
    otherwise) and its level sizes."""
    GL = lazy_gl()
    target = GL.GL_TEXTURE_2D if target is None else target
    binding = (
        GL.GL_TEXTURE_BINDING_2D if target == GL.GL_TEXTURE_2D else GL.GL_TEXTURE_BINDING_CUBE_MAP
    )
    image_target = target if target == GL.GL_TEXTURE_2D else GL.GL_TEXTURE_CUBE_MAP_POSITIVE_X
    previous = int(GL.glGetIntegerv(binding))
    GL.glBindTexture(target, int(texture_id))
    values = {
        key: legacy.tex_parameter(target, getattr(GL, key))
        for key in (
            "GL_TEXTURE_MIN_FILTER",
            "GL_TEXTURE_MAG_FILTER",
            "GL_TEXTURE_WRAP_S",
            "GL_TEXTURE_WRAP_T",
            "GL_TEXTURE_MAX_LEVEL",
            "GL_TEXTURE_BASE_LEVEL",
        )
    }
    for level, key in ((0, "width"), (1, "level1_width")):
        values[key] = int(GL.glGetTexLevelParameteriv(image_target, level, GL.GL_TEXTURE_WIDTH))
    values["height"] = int(GL.glGetTexLevelParameteriv(image_target, 0, GL.GL_TEXTURE_HEIGHT))
    GL.glBindTexture(target, previous)
    return values


# ------------------------------------------------------------------------------ sessions
class LabBase:
    """A lab's session in the current context: a target of ``size`` pixels, the given
    shaders and meshes, the variant's numbers."""

    name = ""
    FOVY, NEAR, FAR = 45.0, 0.1, 100.0
    EYE: tuple[float, float, float] = (0.0, 0.0, 1.0)
    TARGET: tuple[float, float, float] = (0.0, 0.0, 0.0)
    BACKGROUND = (0.0, 0.0, 0.0)

    def __init__(self, size: tuple[int, int], variant: Variant) -> None:
        GL = lazy_gl()
        legacy.start()
        self.width, self.height = int(size[0]), int(size[1])
        self.variant = variant
        self._meshes: dict[str, Mesh] = {}
        self._programs: dict[str, int] = {}
        self.scene_program = compile_program("kit_scene.vert", "kit_scene.frag")
        GL.glUseProgram(self.scene_program)
        GL.glUniform1i(uniform(self.scene_program, "surface"), 0)
        GL.glUseProgram(0)
        GL.glViewport(0, 0, self.width, self.height)
        GL.glEnable(GL.GL_DEPTH_TEST)

    def student_values(self) -> dict[str, Any]:
        """What the student's lab object holds (numbers a student may read)."""
        return {"width": self.width, "height": self.height}

    def programs(self) -> set[int]:
        """Programs the student may use (glUseProgram)."""
        return set()

    def mesh(self, name: str) -> Mesh:
        if name not in self._meshes:
            self._meshes[name] = Mesh(name)
        return self._meshes[name]

    def student_program(
        self, vertex: str, fragment: str, glsl: str, variable: str, limit: int
    ) -> int:
        """The kit's program around the student's GLSL ``glsl`` (compiled once per text;
        at most ``limit`` texts a run)."""
        if not isinstance(glsl, str):
            raise LabSetupError(f"{variable} must be a string of GLSL, got {type(glsl).__name__}")
        if glsl not in self._programs:
            if len(self._programs) >= limit:
                raise LabSetupError(f"more than {limit} different {variable} strings in one run")
            from mirrorlab.labs.trusted.glslcheck import precompile

            # where a bomb or an endless loop costs the file only; probed there too
            precompile(vertex, fragment, glsl, variable, lab=self.name)
            self._programs[glsl] = compile_program(vertex, fragment, glsl, variable)
        return self._programs[glsl]

    def load_picture_texture(self, texture_id: int, name: str) -> None:
        GL = lazy_gl()
        GL.glActiveTexture(GL.GL_TEXTURE0)
        upload_picture(texture_id, name)

    def draw_parts(self, parts, light_world=(0.45, 0.8, 0.4)) -> list[int]:
        """Lit parts ``(mesh name, model (4, 4), colour, GL texture or None)`` under the
        current fixed-function matrices, object textures on unit 0; leaves unit 0 active
        and the last texture bound there. Returns the textures it bound."""
        GL = lazy_gl()
        _, modelview = current_matrices()
        light = np.asarray(light_world, dtype=np.float64)
        light_eye = modelview[:3, :3] @ (light / np.linalg.norm(light))
        program = self.scene_program
        previous_program = int(GL.glGetIntegerv(GL.GL_CURRENT_PROGRAM))
        GL.glUseProgram(program)
        GL.glUniform3f(uniform(program, "light_eye"), *(float(v) for v in light_eye))
        GL.glUniform1f(uniform(program, "ambient"), 0.3)
        GL.glUniform1f(uniform(program, "diffuse"), 0.7)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        bound = []
        with kit_state():
            for mesh, model, color, texture in parts:
                with modelview_times(model):
                    legacy.load_matrix_uniforms(program)
                    GL.glUniform3f(uniform(program, "color"), *(float(c) for c in color))
                    textured = texture is not None and int(texture) > 0
                    GL.glUniform1i(uniform(program, "use_texture"), int(textured))
                    if textured:
                        GL.glBindTexture(GL.GL_TEXTURE_2D, int(texture))
                        bound.append(int(texture))
                    self.mesh(mesh).draw()
        GL.glUseProgram(previous_program)
        return bound

    @classmethod
    def viewer_for(
        cls, size: tuple[int, int], aspect: float | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """The viewer's (projection, view), row-major ``(4, 4)``, for a ``size`` (w, h)
        frame (or ``aspect``)."""
        aspect = aspect if aspect is not None else size[0] / size[1]
        return (
            math3d.perspective(cls.FOVY, aspect, cls.NEAR, cls.FAR),
            math3d.look_at(cls.EYE, cls.TARGET, (0.0, 1.0, 0.0)),
        )

    def viewer_matrices(self, aspect: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        return self.viewer_for((self.width, self.height), aspect)

    def set_viewer(self, aspect: float | None = None) -> None:
        """The viewer's projection and camera; leaves the modelview matrix current."""
        projection, view = self.viewer_matrices(aspect)
        load_matrix(lazy_gl().GL_PROJECTION, projection)
        load_matrix(lazy_gl().GL_MODELVIEW, view)


def open_session(lab: str, size: tuple[int, int], variant: Variant) -> LabBase:
    """The session of ``lab`` for ``variant`` in the current context: its lab's
    ``trusted.SESSION`` (the registry's)."""
    from mirrorlab.labs import find_lab

    session: LabBase = find_lab(lab).module("trusted").SESSION(size, variant)
    return session
