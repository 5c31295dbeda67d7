"""What a lab gives its student, drawn by the trusted side: the context's shaders and
meshes, the robot's scene graph, the cone, the sphere and the viewer's camera, each lab's
numbers taken from its variant (:mod:`.variants`).

A session lives in the executor's GL context (:mod:`.call_executor`); the student's file
reaches its drawing calls (``lab.draw_scene``, ``lab.draw_cone_shader``, ...) only as
messages that the executor validates. Texture units: the given drawing binds object
textures on unit 0 and leaves unit 0 active; the labs keep their environment textures
on unit 1 (the sphere-map lab's texgen cone is textured from the variant's unit).
"""

from __future__ import annotations

import re
from functools import lru_cache
from typing import Any

import numpy as np

from mirrorlab import math3d
from mirrorlab.data import model_file, texture_file
from mirrorlab.labs.trusted import legacy
from mirrorlab.labs.trusted.compat_glsl import TRANSLATED_STATE, translate_compat_glsl
from mirrorlab.labs.trusted.variants import Variant, cube_center, lab20_geometry
from mirrorlab.scene.graph import SceneGraph
from mirrorlab.scene.robot import build_robot

ENV_UNIT = 1
STUDENT_MARK = "// STUDENT CODE"
PICTURES = ("metal", "launch", "wall")
"""The pictures ``lab.load_picture_texture`` may load."""


class LabSetupError(RuntimeError):
    """The lab could not do what was asked (a bad argument, a bad GLSL string); one line."""


class StudentShaderError(LabSetupError):
    """The student's GLSL did not compile: ``variable`` names the Python string, ``line``
    the line inside it (1-based, or 0 when unknown)."""

    def __init__(self, variable: str, line: int, message: str) -> None:
        self.variable, self.line, self.detail = variable, line, message
        where = f"{variable} line {line}" if line else variable
        super().__init__(f"GLSL in {where} did not compile: {message}")


def _gl():
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

    GL = _gl()
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
    of stage ``kind``: the kit file's ``#version`` line, then the text with its
    compatibility built-ins translated, as source string 1 (its lines counted from 1).
    StudentShaderError when it does not compile."""
    stage = "vertex" if kind == _gl().GL_VERTEX_SHADER else "fragment"
    version, _ = student_interface(kit_source)
    source = f"{version}\n#line 1 1\n{translate_compat_glsl(glsl, stage)}\n"
    return _compiled(kind, source, "", variable)


def _text(log: bytes | str) -> str:
    return (log.decode(errors="replace") if isinstance(log, bytes) else str(log)).strip()


def _compiled(kind: int, source: str, what: str, variable: str) -> int:
    """A compiled shader object; ``what`` '' for the student's GLSL."""
    GL = _gl()
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
    GL = _gl()
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
    GL = _gl()
    version_line, prototypes = student_interface(kit_source)
    calls = []
    for result, name, params in prototypes:
        args = [STUB_ARGUMENTS[p.split()[-2]] for p in params.split(",") if p.strip()]
        calls.append(STUB_RESULTS[result].format(f"{name}({', '.join(args)})"))
    declared = "".join(f"{r} {n}({p});\n" for r, n, p in prototypes)
    stub = (
        f"{version_line}\n{declared}out vec4 mirrorlab_stub_out;\nvoid main() {{\n"
        f"    mirrorlab_stub_out = vec4({' + '.join(calls) or '0.0'});\n}}\n"
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
            name = _text(GL.glGetActiveUniform(program, index)[0])
            # GL's own state (gl_ModelViewMatrix, or its translation for a core context)
            # is not the kit's: the same for every draw
            if not name.startswith("gl_") and name.split("[")[0] not in TRANSLATED_STATE:
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
    return int(_gl().glGetUniformLocation(program, name))


def load_matrix(mode: int, matrix: np.ndarray) -> None:
    FF = legacy.gl()
    FF.glMatrixMode(mode)
    FF.glLoadMatrixd(np.ascontiguousarray(np.asarray(matrix, dtype=np.float64).T))


def current_matrices() -> tuple[np.ndarray, np.ndarray]:
    """The fixed-function (projection, modelview) matrices now, ``(4, 4)`` each, row-major
    (the emulated ones on a core context: :mod:`.legacy`)."""
    return legacy.current_matrices()


class _Mesh:
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
        GL = _gl()
        GL.glBindVertexArray(self.vao)
        GL.glDrawElements(GL.GL_TRIANGLES, self.count, GL.GL_UNSIGNED_INT, None)
        GL.glBindVertexArray(0)


@lru_cache(maxsize=32)
def mesh_arrays(name: str) -> tuple[np.ndarray, np.ndarray]:
    """The shipped mesh ``name`` as interleaved float32 vertices and uint32 indices (read
    once a process: a checker process kept for many runs reads each file once)."""
    from mirrorlab.scene.mesh import load_mesh

    data = load_mesh(model_file(name))
    return (
        np.ascontiguousarray(data.interleaved(), dtype=np.float32),
        np.ascontiguousarray(data.indices.reshape(-1), dtype=np.uint32),
    )


@lru_cache(maxsize=8)
def picture(name: str) -> np.ndarray:
    """``textures/<name>.png`` as ``(h, w, 3)`` uint8, row 0 at the top."""
    from mirrorlab.scene.backgrounds import load_picture

    return load_picture(texture_file(name))


def upload_picture(texture_id: int, image: np.ndarray) -> None:
    """Fill GL texture ``texture_id`` (bound on the active unit) with ``image``: mipmapped,
    repeating, trilinear."""
    GL = _gl()
    GL.glBindTexture(GL.GL_TEXTURE_2D, int(texture_id))
    GL.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 1)
    GL.glTexImage2D(
        GL.GL_TEXTURE_2D,
        0,
        GL.GL_RGB8,
        image.shape[1],
        image.shape[0],
        0,
        GL.GL_RGB,
        GL.GL_UNSIGNED_BYTE,
        np.ascontiguousarray(image[::-1]),
    )
    GL.glGenerateMipmap(GL.GL_TEXTURE_2D)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_LINEAR_MIPMAP_LINEAR)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_LINEAR)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_S, GL.GL_REPEAT)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_T, GL.GL_REPEAT)


def read_texture_2d(texture_id: int, level: int = 0) -> np.ndarray:
    """Level ``level`` of 2D texture ``texture_id`` as ``(h, w, 3)`` uint8, row 0 at the
    top; (0, 0, 3) when it has no storage. Keeps the active unit's binding."""
    GL = _gl()
    previous = int(GL.glGetIntegerv(GL.GL_TEXTURE_BINDING_2D))
    GL.glBindTexture(GL.GL_TEXTURE_2D, int(texture_id))
    width = int(GL.glGetTexLevelParameteriv(GL.GL_TEXTURE_2D, level, GL.GL_TEXTURE_WIDTH))
    height = int(GL.glGetTexLevelParameteriv(GL.GL_TEXTURE_2D, level, GL.GL_TEXTURE_HEIGHT))
    image = np.zeros((0, 0, 3), dtype=np.uint8)
    if width > 0 and height > 0:
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        data = GL.glGetTexImage(GL.GL_TEXTURE_2D, level, GL.GL_RGB, GL.GL_UNSIGNED_BYTE)
        image = np.frombuffer(data, dtype=np.uint8).reshape(height, width, 3)[::-1].copy()
    GL.glBindTexture(GL.GL_TEXTURE_2D, previous)
    return image


def read_cube_faces(texture: int) -> np.ndarray | None:
    """The six level-0 faces of cube map ``texture``, ``(6, n, n, 3)`` uint8 (row 0 at
    ``t = 1``), or None when they are not all the same square size."""
    GL = _gl()
    previous = int(GL.glGetIntegerv(GL.GL_TEXTURE_BINDING_CUBE_MAP))
    GL.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, texture)
    faces: list[np.ndarray] = []
    try:
        for face in range(6):
            target = GL.GL_TEXTURE_CUBE_MAP_POSITIVE_X + face
            width = int(GL.glGetTexLevelParameteriv(target, 0, GL.GL_TEXTURE_WIDTH))
            height = int(GL.glGetTexLevelParameteriv(target, 0, GL.GL_TEXTURE_HEIGHT))
            if width == 0 or width != height or (faces and faces[0].shape[0] != width):
                return None
            GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
            data = GL.glGetTexImage(target, 0, GL.GL_RGB, GL.GL_UNSIGNED_BYTE)
            faces.append(np.frombuffer(data, dtype=np.uint8).reshape(width, width, 3)[::-1])
    finally:
        GL.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, previous)
    return np.stack(faces)


def texture_parameters(texture_id: int, target: int | None = None) -> dict[str, int]:
    """The sampling parameters of ``texture_id`` (a 2D texture unless ``target`` says
    otherwise) and its level sizes."""
    GL = _gl()
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
        GL = _gl()
        legacy.start()
        self.width, self.height = int(size[0]), int(size[1])
        self.variant = variant
        self._meshes: dict[str, _Mesh] = {}
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

    def mesh(self, name: str) -> _Mesh:
        if name not in self._meshes:
            self._meshes[name] = _Mesh(name)
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

            precompile(vertex, fragment, glsl, variable)  # where a bomb costs the file only
            self._programs[glsl] = compile_program(vertex, fragment, glsl, variable)
        return self._programs[glsl]

    def load_picture_texture(self, texture_id: int, name: str) -> None:
        GL = _gl()
        GL.glActiveTexture(GL.GL_TEXTURE0)
        upload_picture(texture_id, picture(name))

    def draw_parts(self, parts, light_world=(0.45, 0.8, 0.4)) -> list[int]:
        """Lit parts ``(mesh name, model (4, 4), colour, GL texture or None)`` under the
        current fixed-function matrices, object textures on unit 0; leaves unit 0 active
        and the last texture bound there. Returns the textures it bound."""
        GL = _gl()
        _, modelview = current_matrices()
        light = np.asarray(light_world, dtype=np.float64)
        light_eye = modelview[:3, :3] @ (light / np.linalg.norm(light))
        program = self.scene_program
        previous_program = int(GL.glGetIntegerv(GL.GL_CURRENT_PROGRAM))
        GL.glUseProgram(program)
        GL.glUniform3f(uniform(program, "light_eye"), *(float(v) for v in light_eye))
        GL.glUniform1f(uniform(program, "ambient"), 0.3)
        GL.glUniform1f(uniform(program, "diffuse"), 0.7)
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        FF = legacy.gl()
        FF.glMatrixMode(GL.GL_MODELVIEW)
        bound = []
        for mesh, model, color, texture in parts:
            FF.glPushMatrix()
            FF.glMultMatrixd(np.ascontiguousarray(np.asarray(model, dtype=np.float64).T))
            legacy.load_matrix_uniforms(program)
            GL.glUniform3f(uniform(program, "color"), *(float(c) for c in color))
            textured = texture is not None and int(texture) > 0
            GL.glUniform1i(uniform(program, "use_texture"), int(textured))
            if textured:
                GL.glBindTexture(GL.GL_TEXTURE_2D, int(texture))
                bound.append(int(texture))
            self.mesh(mesh).draw()
            FF.glPopMatrix()
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
        load_matrix(_gl().GL_PROJECTION, projection)
        load_matrix(_gl().GL_MODELVIEW, view)


class Lab20(LabBase):
    """Lab 20, the multipass mirror: the robot on its base at the variant's pose, a dark
    frame behind the variant's mirror, the viewer, and ``textureShader`` (sampler
    uniform ``texSampler``) for the mirror quad."""

    name = "lab20"
    EYE = (12.0, 5.0, 9.0)
    TARGET = (-3.5, 1.0, -2.0)
    FOVY, NEAR, FAR = 45.0, 0.1, 100.0
    BACKGROUND = (0.16, 0.18, 0.22)
    NODES = ("base", "shoulder", "lower_arm", "elbow", "upper_arm", "hand")

    def __init__(self, size: tuple[int, int], variant: Variant) -> None:
        super().__init__(size, variant)
        self.geometry = lab20_geometry(variant)
        self.textureShader = compile_program("kit_texture.vert", "kit_texture.frag")
        self.texSampler = uniform(self.textureShader, "texSampler")
        self.graph = SceneGraph(build_robot())
        for joint, angle in zip(
            ("base", "lower_arm", "upper_arm"), self.geometry["angles"], strict=True
        ):
            self.graph.set_angle(joint, angle)
        _gl().glClearColor(*self.BACKGROUND, 1.0)

    def student_values(self) -> dict[str, Any]:
        return {
            **super().student_values(),
            "textureShader": self.textureShader,
            "texSampler": self.texSampler,
            "robot_nodes": list(self.NODES),
        }

    def programs(self) -> set[int]:
        return {self.textureShader}

    def frame_model(self) -> np.ndarray:
        """The mirror frame's model: the shipped 8.6 x 8.6 frame (8 x 8 glass and a 0.3
        border) scaled to the variant's mirror, just behind its plane."""
        g = self.geometry
        scale = np.diag(
            [1.0, (g["y1"] - g["y0"] + 0.6) / 8.6, (g["z1"] - g["z0"] + 0.6) / 8.6, 1.0]
        )
        return math3d.translate((g["x"] - 0.175, g["y0"] - 0.3, (g["z0"] + g["z1"]) / 2)) @ scale

    def draw_scene(self, textures: dict[str, int | None]) -> list[int]:
        """The robot, each node wearing ``textures[node]``, and the mirror's frame, lit,
        under the current matrices. Never the mirror."""
        parts = []
        for node in self.graph.nodes():
            if node.mesh:
                parts.append((node.mesh, node.world_matrix(), node.color, textures.get(node.name)))
        parts.append(("mirror_frame", self.frame_model(), (0.35, 0.27, 0.2), None))
        return self.draw_parts(parts)


class SphereMapLab(LabBase):
    """The textbook's cone (Guha 13.6) in front of the launch picture: the cone drawn by the
    student's shader functions, or by fixed-function texgen on the variant's unit."""

    name = "spheremap"
    EYE = (0.0, 1.0, 7.0)
    TARGET = (0.0, 0.6, 0.0)
    FOVY, NEAR, FAR = 45.0, 0.5, 60.0
    BACKDROP_MODEL = math3d.translate((0.0, 0.0, -8.0))

    def __init__(self, size: tuple[int, int], variant: Variant) -> None:
        super().__init__(size, variant)
        self.cone_model = math3d.translate((0.0, 1.0, 0.0)) @ math3d.rotate(
            float(variant["tilt"]), (1.0, 0.0, 0.0)
        )
        self.texgen_unit = int(variant["unit"])
        self.backdrop_texture = int(_gl().glGenTextures(1))
        self.load_picture_texture(self.backdrop_texture, "launch")

    def draw_backdrop(self) -> list[int]:
        """The launch picture on its board behind the cone, lit, under the current matrices."""
        return self.draw_parts(
            [("backdrop", self.BACKDROP_MODEL, (1.0, 1.0, 1.0), self.backdrop_texture)],
            light_world=(0.0, 0.0, 1.0),
        )

    def draw_cone_shader(self, glsl: str, texture: int, mode: int = 0, limit: int = 16) -> None:
        """The cone drawn by the kit's shader calling the student's ``reflect_eye`` and
        ``sphere_map_st`` (from ``glsl``), sampling ``texture`` on unit 1, under the
        current matrices. (``mode`` 1-4 write check values instead of colours.)"""
        GL = _gl()
        program = self.student_program(
            "kit_sphere.vert", "kit_sphere.frag", glsl, "SPHERE_MAP_GLSL", limit
        )
        previous = int(GL.glGetIntegerv(GL.GL_CURRENT_PROGRAM))
        GL.glUseProgram(program)
        GL.glUniform1i(uniform(program, "sphere_map"), ENV_UNIT)
        GL.glUniform1i(uniform(program, "mode"), int(mode))
        GL.glActiveTexture(GL.GL_TEXTURE0 + ENV_UNIT)
        GL.glBindTexture(GL.GL_TEXTURE_2D, int(texture))
        GL.glActiveTexture(GL.GL_TEXTURE0)
        FF = legacy.gl()
        FF.glMatrixMode(GL.GL_MODELVIEW)
        FF.glPushMatrix()
        FF.glMultMatrixd(np.ascontiguousarray(self.cone_model.T))
        legacy.load_matrix_uniforms(program)
        self.mesh("cone").draw()
        FF.glPopMatrix()
        GL.glUseProgram(previous)

    def draw_cone_fixed_function(self) -> None:
        """The cone with no shader, in the fixed-function pipeline: its texture coordinates
        whatever texgen makes of them on the variant's unit, textured there (GL_REPLACE);
        every other unit's texturing off while it is drawn."""
        GL = _gl()
        previous = int(GL.glGetIntegerv(GL.GL_CURRENT_PROGRAM))
        active = int(GL.glGetIntegerv(GL.GL_ACTIVE_TEXTURE))
        GL.glUseProgram(0)
        FF = legacy.gl()
        FF.glDisable(GL.GL_LIGHTING)
        FF.glEnable(GL.GL_NORMALIZE)
        enabled = []
        for unit in range(4):
            GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
            for cap in (GL.GL_TEXTURE_2D, GL.GL_TEXTURE_CUBE_MAP):
                if FF.glIsEnabled(cap):
                    enabled.append((unit, cap))
                    FF.glDisable(cap)
        GL.glActiveTexture(GL.GL_TEXTURE0 + self.texgen_unit)
        FF.glEnable(GL.GL_TEXTURE_2D)
        FF.glTexEnvi(GL.GL_TEXTURE_ENV, GL.GL_TEXTURE_ENV_MODE, GL.GL_REPLACE)
        FF.glMatrixMode(GL.GL_MODELVIEW)
        FF.glPushMatrix()
        FF.glMultMatrixd(np.ascontiguousarray(self.cone_model.T))
        mesh = self.mesh("cone")
        emulation = legacy.emulated()
        if emulation is not None:
            emulation.draw_elements(mesh.vao, mesh.count)
        else:
            self._draw_client_arrays(mesh)
        FF.glPopMatrix()
        FF.glDisable(GL.GL_TEXTURE_2D)
        for unit, cap in enabled:
            GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
            FF.glEnable(cap)
        GL.glActiveTexture(active)
        FF.glDisable(GL.GL_NORMALIZE)
        GL.glUseProgram(previous)

    @staticmethod
    def _draw_client_arrays(mesh: _Mesh) -> None:
        """The cone from client-state arrays (the compatibility profile's own pipeline)."""
        GL = _gl()
        GL.glBindVertexArray(0)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, mesh.vbo)
        GL.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, mesh.ebo)
        for array in (
            GL.GL_COLOR_ARRAY,
            GL.GL_TEXTURE_COORD_ARRAY,
            GL.GL_INDEX_ARRAY,
            GL.GL_EDGE_FLAG_ARRAY,
            GL.GL_FOG_COORD_ARRAY,
            GL.GL_SECONDARY_COLOR_ARRAY,
        ):
            GL.glDisableClientState(array)
        GL.glEnableClientState(GL.GL_VERTEX_ARRAY)
        GL.glVertexPointer(3, GL.GL_FLOAT, 32, GL.GLvoidp(0))
        GL.glEnableClientState(GL.GL_NORMAL_ARRAY)
        GL.glNormalPointer(GL.GL_FLOAT, 32, GL.GLvoidp(12))
        GL.glDrawElements(GL.GL_TRIANGLES, mesh.count, GL.GL_UNSIGNED_INT, None)
        GL.glDisableClientState(GL.GL_VERTEX_ARRAY)
        GL.glDisableClientState(GL.GL_NORMAL_ARRAY)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, 0)
        GL.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, 0)


class CubeMapLab(LabBase):
    """A chrome sphere on a pedestal among four coloured objects: the sphere, at the
    variant's centre, drawn by the kit's shader through the student's face selection."""

    name = "cubemap"
    EYE = (1.3, 2.0, 7.4)
    TARGET = (0.0, 0.1, 0.0)
    FOVY, NEAR, FAR = 38.0, 0.2, 60.0
    BACKGROUND = (0.55, 0.7, 0.9)
    OBJECTS = (
        ("base", math3d.translate((0.0, -1.25, 0.0)), (1.0, 1.0, 1.0), "metal"),
        (
            "hand",
            math3d.translate((2.1, 0.1, 0.9)) @ math3d.rotate(30.0, (0, 1, 0)),
            (0.9, 0.12, 0.1),
            None,
        ),
        ("joint", math3d.translate((-1.9, 0.9, 1.3)), (0.15, 0.35, 0.95), None),
        (
            "lower_arm",
            math3d.translate((0.6, -1.25, -2.6)) @ math3d.rotate(20.0, (0, 1, 0)),
            (0.95, 0.75, 0.15),
            None,
        ),
        (
            "upper_arm",
            math3d.translate((-2.4, -1.25, -1.0)) @ math3d.rotate(-35.0, (0, 1, 0)),
            (0.2, 0.75, 0.3),
            None,
        ),
        ("backdrop", math3d.translate((0.0, 0.0, -9.0)), (0.85, 0.85, 0.85), "launch"),
    )

    def __init__(self, size: tuple[int, int], variant: Variant) -> None:
        super().__init__(size, variant)
        self.center = cube_center(variant)
        self._textures: dict[str, int] = {}
        for name in ("metal", "launch"):
            texture = int(_gl().glGenTextures(1))
            self.load_picture_texture(texture, name)
            self._textures[name] = texture

    def student_values(self) -> dict[str, Any]:
        return {**super().student_values(), "BACKGROUND": list(self.BACKGROUND)}

    def draw_scene(self) -> list[int]:
        """The pedestal (under the sphere), the four objects and the picture behind them,
        lit, under the current matrices. Never the sphere."""
        pedestal = math3d.translate((self.center[0], 0.0, self.center[2]))
        parts = []
        for mesh, model, color, texture in self.OBJECTS:
            model = pedestal @ model if mesh == "base" else model
            parts.append((mesh, model, color, self._textures.get(texture or "")))
        return self.draw_parts(parts, light_world=(0.45, 0.55, 0.7))

    def draw_sphere(self, glsl: str, cube_texture: int, mode: int = 0, limit: int = 16) -> None:
        """The chrome sphere at the variant's centre, drawn by the kit's shader: it reflects
        the eye ray in world space, asks the student's ``cube_face`` and ``cube_face_st``
        (from ``glsl``) where that lands, and samples ``cube_texture`` (a cube map, on
        unit 1) there. (``mode`` 1-2 write check values instead of colours.)"""
        GL = _gl()
        program = self.student_program(
            "kit_cube.vert", "kit_cube.frag", glsl, "CUBE_MAP_GLSL", limit
        )
        projection, modelview = current_matrices()
        eye = -modelview[:3, :3].T @ modelview[:3, 3]
        previous = int(GL.glGetIntegerv(GL.GL_CURRENT_PROGRAM))
        GL.glUseProgram(program)
        GL.glUniform1i(uniform(program, "cube_map"), ENV_UNIT)
        GL.glUniform1i(uniform(program, "mode"), int(mode))
        GL.glUniform3f(uniform(program, "eye_world"), *(float(v) for v in eye))
        GL.glUniform3f(uniform(program, "center"), *(float(v) for v in self.center))
        GL.glUniformMatrix4fv(
            uniform(program, "view_projection"),
            1,
            GL.GL_TRUE,
            (projection @ modelview).astype(np.float32),
        )
        GL.glActiveTexture(GL.GL_TEXTURE0 + ENV_UNIT)
        GL.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, int(cube_texture))
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glEnable(GL.GL_TEXTURE_CUBE_MAP_SEAMLESS)
        legacy.load_matrix_uniforms(program)
        self.mesh("env_sphere").draw()
        GL.glUseProgram(previous)


SESSIONS = {"lab20": Lab20, "spheremap": SphereMapLab, "cubemap": CubeMapLab}


def open_session(lab: str, size: tuple[int, int], variant: Variant) -> LabBase:
    """The session of ``lab`` for ``variant`` in the current context."""
    return SESSIONS[lab](size, variant)
