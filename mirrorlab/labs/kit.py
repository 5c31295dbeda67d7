"""What a lab gives its student: the OpenGL context, the shaders, the meshes, the robot's
scene graph and the viewer's camera, so that a student's file holds only the lab's own steps.

A student's file starts with ``lab = kit.lab20()`` (or ``kit.spheremap()``,
``kit.cubemap()``) and calls plain PyOpenGL in the compatibility profile around what the
lab object offers. ``mirrorlab lab check`` and ``mirrorlab lab run`` open the session
(headless or in a window) before the student's file runs; the lab object also notes what
the given drawing calls see (the matrices, the texture state) for the checker.

Texture units: the given drawing code binds object textures (METAL, the launch picture)
on unit 0; the labs keep their environment textures on unit 1.
"""

from __future__ import annotations

import sys
from typing import Any

import numpy as np

from mirrorlab import math3d
from mirrorlab.data import model_file, texture_file
from mirrorlab.scene.graph import SceneGraph
from mirrorlab.scene.robot import build_robot

ENV_UNIT = 1
"""The texture unit the labs keep their environment texture on."""

STUDENT_MARK = "// STUDENT CODE"
"""The line of a kit shader where the student's GLSL goes."""


class LabSetupError(RuntimeError):
    """The lab could not be set up (no session open, a bad GLSL string); one line."""


class StudentShaderError(LabSetupError):
    """The student's GLSL did not compile: ``variable`` names the Python string,
    ``line`` the line inside it (1-based, or 0 when unknown)."""

    def __init__(self, variable: str, line: int, message: str) -> None:
        self.variable, self.line = variable, line
        where = f"{variable} line {line}" if line else variable
        super().__init__(f"GLSL in {where} did not compile: {message}")


_session: LabBase | None = None


def _current(kind: type) -> Any:
    if _session is None or not isinstance(_session, kind):
        raise LabSetupError(
            "no lab session is open: run this file with 'mirrorlab lab run LAB FILE' or "
            "check it with 'mirrorlab lab check LAB FILE'")
    return _session


def lab20() -> Lab20:
    """The session of lab 20 (the multipass mirror)."""
    return _current(Lab20)


def spheremap() -> SphereMapLab:
    """The session of the sphere-map lab."""
    return _current(SphereMapLab)


def cubemap() -> CubeMapLab:
    """The session of the cube-map lab."""
    return _current(CubeMapLab)


# ------------------------------------------------------------------------------- GL helpers


def _gl():
    from mirrorlab.gl.opengl import GL

    return GL


def compile_program(vertex: str, fragment: str, student: str | None = None,
                    variable: str = "") -> int:
    """A linked program from package shader files (``#include`` expanded); ``student`` GLSL
    replaces the :data:`STUDENT_MARK` line of either file. Returns the GL program name."""
    from mirrorlab.gl.resources import expand_includes

    GL = _gl()
    shaders = []
    for name, kind in ((vertex, GL.GL_VERTEX_SHADER), (fragment, GL.GL_FRAGMENT_SHADER)):
        source = expand_includes(name)
        offset = 0
        if student is not None and STUDENT_MARK in source:
            before = source.split(STUDENT_MARK)[0]
            offset = before.count("\n")
            source = source.replace(STUDENT_MARK, f"#line 1 1\n{student}\n#line "
                                    f"{offset + 2} 0\n")
        shader = GL.glCreateShader(kind)
        GL.glShaderSource(shader, source)
        GL.glCompileShader(shader)
        if not GL.glGetShaderiv(shader, GL.GL_COMPILE_STATUS):
            log = GL.glGetShaderInfoLog(shader).decode(errors="replace").strip()
            GL.glDeleteShader(shader)
            if student is not None:
                raise StudentShaderError(variable, *_student_log_line(log))
            raise LabSetupError(f"kit shader {name} did not compile: {log}")
        shaders.append(shader)
    program = GL.glCreateProgram()
    for shader in shaders:
        GL.glAttachShader(program, shader)
    GL.glLinkProgram(program)
    for shader in shaders:
        GL.glDeleteShader(shader)
    if not GL.glGetProgramiv(program, GL.GL_LINK_STATUS):
        log = GL.glGetProgramInfoLog(program).decode(errors="replace").strip()
        if student is not None:
            raise StudentShaderError(variable, 0, log.splitlines()[0] if log else "link failed")
        raise LabSetupError(f"kit program {vertex}+{fragment} did not link: {log}")
    return int(program)


def _student_log_line(log: str) -> tuple[int, str]:
    """(line in the student's string, first message) from a Mesa compile log whose student
    part was compiled as source string 1."""
    import re

    for line in log.splitlines():
        match = re.match(r"\s*(\d+):(\d+)\((\d+)\):\s*(.*)", line)
        if match and match.group(1) == "1":
            return int(match.group(2)), match.group(4)
    first = log.splitlines()[0] if log else "compile failed"
    return 0, first


def _uniform(program: int, name: str) -> int:
    return int(_gl().glGetUniformLocation(program, name))


def _load_matrix(mode: int, matrix: np.ndarray) -> None:
    GL = _gl()
    GL.glMatrixMode(mode)
    GL.glLoadMatrixd(np.ascontiguousarray(np.asarray(matrix, dtype=np.float64).T))


def current_matrices() -> tuple[np.ndarray, np.ndarray]:
    """The fixed-function (projection, modelview) matrices now, ``(4, 4)`` each, row-major."""
    GL = _gl()
    projection = np.asarray(GL.glGetDoublev(GL.GL_PROJECTION_MATRIX), dtype=np.float64)
    modelview = np.asarray(GL.glGetDoublev(GL.GL_MODELVIEW_MATRIX), dtype=np.float64)
    return projection.reshape(4, 4).T.copy(), modelview.reshape(4, 4).T.copy()


class _Mesh:
    """One mesh file in a vertex buffer, drawn with generic attributes 0 (position),
    1 (normal) and 2 (texture coordinate), which the compatibility profile's
    ``gl_Vertex`` aliases too."""

    def __init__(self, name: str) -> None:
        from mirrorlab.gl.resources import upload_mesh
        from mirrorlab.scene.mesh import load_mesh

        data = load_mesh(model_file(name))
        vertices = np.ascontiguousarray(data.interleaved(), dtype=np.float32)
        indices = np.ascontiguousarray(data.indices.reshape(-1), dtype=np.uint32)
        self.count = int(indices.size)
        # the session's meshes live as long as its process: no registry, nothing to free
        self.vao, self.vbo, self.ebo = upload_mesh(vertices, indices)

    def draw(self) -> None:
        GL = _gl()
        GL.glBindVertexArray(self.vao)
        GL.glDrawElements(GL.GL_TRIANGLES, self.count, GL.GL_UNSIGNED_INT, None)
        GL.glBindVertexArray(0)


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
    GL.glTexImage2D(GL.GL_TEXTURE_2D, 0, GL.GL_RGB8, image.shape[1], image.shape[0], 0,
                    GL.GL_RGB, GL.GL_UNSIGNED_BYTE, np.ascontiguousarray(image[::-1]))
    GL.glGenerateMipmap(GL.GL_TEXTURE_2D)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_LINEAR_MIPMAP_LINEAR)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_LINEAR)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_S, GL.GL_REPEAT)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_T, GL.GL_REPEAT)


def read_texture_2d(texture_id: int) -> np.ndarray:
    """Level 0 of 2D texture ``texture_id`` as ``(h, w, 3)`` uint8, row 0 at the top; (0, 0, 3)
    when it has no storage. Keeps the active unit's binding."""
    GL = _gl()
    previous = int(GL.glGetIntegerv(GL.GL_TEXTURE_BINDING_2D))
    GL.glBindTexture(GL.GL_TEXTURE_2D, int(texture_id))
    width = int(GL.glGetTexLevelParameteriv(GL.GL_TEXTURE_2D, 0, GL.GL_TEXTURE_WIDTH))
    height = int(GL.glGetTexLevelParameteriv(GL.GL_TEXTURE_2D, 0, GL.GL_TEXTURE_HEIGHT))
    image = np.zeros((0, 0, 3), dtype=np.uint8)
    if width > 0 and height > 0:
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        data = GL.glGetTexImage(GL.GL_TEXTURE_2D, 0, GL.GL_RGB, GL.GL_UNSIGNED_BYTE)
        image = np.frombuffer(data, dtype=np.uint8).reshape(height, width, 3)[::-1].copy()
    GL.glBindTexture(GL.GL_TEXTURE_2D, previous)
    return image


def texture_parameters(texture_id: int) -> dict[str, int]:
    """The sampling parameters of 2D texture ``texture_id`` and whether level 1 exists."""
    GL = _gl()
    previous = int(GL.glGetIntegerv(GL.GL_TEXTURE_BINDING_2D))
    GL.glBindTexture(GL.GL_TEXTURE_2D, int(texture_id))
    values = {key: int(np.asarray(GL.glGetTexParameteriv(GL.GL_TEXTURE_2D, getattr(GL, key)))
                       .reshape(-1)[0])
              for key in ("GL_TEXTURE_MIN_FILTER", "GL_TEXTURE_MAG_FILTER",
                          "GL_TEXTURE_WRAP_S", "GL_TEXTURE_WRAP_T", "GL_TEXTURE_MAX_LEVEL")}
    values["level1_width"] = int(GL.glGetTexLevelParameteriv(GL.GL_TEXTURE_2D, 1,
                                                             GL.GL_TEXTURE_WIDTH))
    values["width"] = int(GL.glGetTexLevelParameteriv(GL.GL_TEXTURE_2D, 0, GL.GL_TEXTURE_WIDTH))
    values["height"] = int(GL.glGetTexLevelParameteriv(GL.GL_TEXTURE_2D, 0,
                                                       GL.GL_TEXTURE_HEIGHT))
    GL.glBindTexture(GL.GL_TEXTURE_2D, previous)
    return values


def bound_units(texture_id: int, target_binding: str = "GL_TEXTURE_BINDING_2D") -> list[int]:
    """The texture units (0..7) on which ``texture_id`` is bound now."""
    GL = _gl()
    active = int(GL.glGetIntegerv(GL.GL_ACTIVE_TEXTURE))
    units = []
    for unit in range(8):
        GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
        if int(GL.glGetIntegerv(getattr(GL, target_binding))) == int(texture_id):
            units.append(unit)
    GL.glActiveTexture(active)
    return units


# ------------------------------------------------------------------------------- sessions


class LabBase:
    """A lab's session: a context and a target of ``size`` pixels, the given shaders and
    meshes, and the notes the checker reads (:attr:`events`)."""

    name = ""

    def __init__(self, size: tuple[int, int], window: Any = None) -> None:
        GL = _gl()
        self.width, self.height = int(size[0]), int(size[1])
        self.window = window
        self.events: list[dict[str, Any]] = []
        self.steps: list[str] = []
        self._meshes: dict[str, _Mesh] = {}
        self.scene_program = compile_program("kit_scene.vert", "kit_scene.frag")
        GL.glUseProgram(self.scene_program)
        GL.glUniform1i(_uniform(self.scene_program, "surface"), 0)
        GL.glUseProgram(0)
        GL.glViewport(0, 0, self.width, self.height)
        GL.glEnable(GL.GL_DEPTH_TEST)

    def mesh(self, name: str) -> _Mesh:
        if name not in self._meshes:
            self._meshes[name] = _Mesh(name)
        return self._meshes[name]

    def note(self, kind: str, **values: Any) -> None:
        """Remember what a given call saw, with the student's functions running then."""
        self.events.append({"kind": kind, "steps": list(self.steps), **values})

    def load_picture_texture(self, texture_id: int, name: str) -> None:
        """Fill texture ``texture_id`` with ``textures/<name>.png`` (mipmapped, repeating),
        on texture unit 0."""
        GL = _gl()
        GL.glActiveTexture(GL.GL_TEXTURE0)
        upload_picture(texture_id, picture(name))

    def _draw_parts(self, parts, light_world=(0.45, 0.8, 0.4)) -> None:
        """Lit parts ``(mesh name, model (4, 4), colour, GL texture or None)`` under the
        current fixed-function matrices, object textures on unit 0; leaves unit 0 active
        and the last texture bound there, as the lab's own drawing code does."""
        GL = _gl()
        projection, modelview = current_matrices()
        self.note("draw_scene", projection=projection, modelview=modelview,
                  viewport=[int(v) for v in np.asarray(GL.glGetIntegerv(GL.GL_VIEWPORT))])
        light = np.asarray(light_world, dtype=np.float64)
        light_eye = modelview[:3, :3] @ (light / np.linalg.norm(light))
        program = self.scene_program
        previous_program = int(GL.glGetIntegerv(GL.GL_CURRENT_PROGRAM))
        GL.glUseProgram(program)
        GL.glUniform3f(_uniform(program, "light_eye"), *(float(v) for v in light_eye))
        GL.glUniform1f(_uniform(program, "ambient"), 0.3)
        GL.glUniform1f(_uniform(program, "diffuse"), 0.7)
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glMatrixMode(GL.GL_MODELVIEW)
        for mesh, model, color, texture in parts:
            GL.glPushMatrix()
            GL.glMultMatrixd(np.ascontiguousarray(np.asarray(model, dtype=np.float64).T))
            GL.glUniform3f(_uniform(program, "color"), *(float(c) for c in color))
            textured = texture is not None and int(texture) > 0
            GL.glUniform1i(_uniform(program, "use_texture"), int(textured))
            if textured:
                GL.glBindTexture(GL.GL_TEXTURE_2D, int(texture))
            self.mesh(mesh).draw()
            GL.glPopMatrix()
        GL.glUseProgram(previous_program)

    def read_frame(self) -> np.ndarray:
        """The bound framebuffer's colour, ``(height, width, 3)`` uint8, row 0 at the top."""
        from mirrorlab.gl.resources import read_pixels

        return read_pixels(self.width, self.height)

    def set_camera(self, projection: np.ndarray, view: np.ndarray) -> None:
        _load_matrix(_gl().GL_PROJECTION, projection)
        _load_matrix(_gl().GL_MODELVIEW, view)


# ---------------------------------------------------------------------------------- lab 20


class Lab20(LabBase):
    """Lab 20, the multipass mirror: the robot on its base, a dark frame behind the mirror,
    the viewer's camera, and ``textureShader`` (sampler uniform ``texSampler``) for the
    mirror quad. ``robot`` is the scene graph (``robot["base"].texture`` is a GL texture
    id or None)."""

    name = "lab20"
    EYE = (12.0, 5.0, 9.0)
    TARGET = (-3.5, 1.0, -2.0)
    FOVY, NEAR, FAR = 45.0, 0.1, 100.0
    BACKGROUND = (0.16, 0.18, 0.22)
    ANGLES = (-35.0, 30.0, -75.0)

    def __init__(self, size: tuple[int, int], window: Any = None) -> None:
        super().__init__(size, window)
        self.textureShader = compile_program("kit_texture.vert", "kit_texture.frag")
        self.texSampler = _uniform(self.textureShader, "texSampler")
        self.robot: SceneGraph | None = None
        _gl().glClearColor(*self.BACKGROUND, 1.0)

    def robot_graph(self) -> SceneGraph:
        """The robot's scene graph (base -> lower arm -> upper arm -> hand) at the lab's
        angles, no node textured yet."""
        graph = SceneGraph(build_robot())
        for node in graph.nodes():
            node.texture = None
        for joint, angle in zip(("base", "lower_arm", "upper_arm"), self.ANGLES, strict=True):
            graph.set_angle(joint, angle)
        self.robot = graph
        return graph

    def draw_scene(self, robot: SceneGraph | None = None) -> None:
        """Draw the robot (with its nodes' textures) and the mirror's frame, lit, under the
        current projection and modelview matrices. Never the mirror."""
        robot = robot if robot is not None else self.robot
        if robot is None:
            raise LabSetupError("draw_scene: there is no scene graph yet; "
                                "build_scene_graph() makes it with lab.robot_graph()")
        parts = [(node.mesh, node.world_matrix(), node.color, node.texture)
                 for node in robot.nodes() if node.mesh]
        frame = math3d.translate((-7.175, -3.3, -2.0))
        parts.append(("mirror_frame", frame, (0.35, 0.27, 0.2), None))
        self._draw_parts(parts)

    def viewer_matrices(self) -> tuple[np.ndarray, np.ndarray]:
        return (math3d.perspective(self.FOVY, self.width / self.height, self.NEAR, self.FAR),
                math3d.look_at(self.EYE, self.TARGET, (0.0, 1.0, 0.0)))

    def set_viewer(self) -> None:
        """The viewer's projection and camera (the matrices of the camera pass)."""
        self.set_camera(*self.viewer_matrices())


# ------------------------------------------------------------------------- sphere-map lab


class SphereMapLab(LabBase):
    """The textbook's cone (Guha 13.6) in front of the launch picture: the cone drawn by your
    shader functions, or by fixed-function texgen."""

    name = "spheremap"
    EYE = (0.0, 1.0, 7.0)
    TARGET = (0.0, 0.6, 0.0)
    FOVY, NEAR, FAR = 45.0, 0.5, 60.0
    CONE_MODEL = math3d.translate((0.0, 1.0, 0.0)) @ math3d.rotate(50.0, (1.0, 0.0, 0.0))
    BACKDROP_MODEL = math3d.translate((0.0, 0.0, -8.0))

    def __init__(self, size: tuple[int, int], window: Any = None) -> None:
        super().__init__(size, window)
        self._programs: dict[str, int] = {}
        self.backdrop_texture = int(_gl().glGenTextures(1))
        self.load_picture_texture(self.backdrop_texture, "launch")

    def viewer_matrices(self, aspect: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        aspect = aspect if aspect is not None else self.width / self.height
        return (math3d.perspective(self.FOVY, aspect, self.NEAR, self.FAR),
                math3d.look_at(self.EYE, self.TARGET, (0.0, 1.0, 0.0)))

    def set_viewer(self, aspect: float | None = None) -> None:
        """The viewer's projection (for ``aspect``, default the target's) and camera."""
        self.set_camera(*self.viewer_matrices(aspect))

    def draw_backdrop(self) -> None:
        """The launch picture on its board behind the cone, lit, under the current matrices."""
        self._draw_parts([("backdrop", self.BACKDROP_MODEL, (1.0, 1.0, 1.0),
                           self.backdrop_texture)], light_world=(0.0, 0.0, 1.0))

    def _program(self, glsl: str, variable: str) -> int:
        if not isinstance(glsl, str):
            raise LabSetupError(f"{variable} must be a string of GLSL, got {type(glsl).__name__}")
        if glsl not in self._programs:
            self._programs[glsl] = compile_program("kit_sphere.vert", "kit_sphere.frag",
                                                   glsl, variable)
        return self._programs[glsl]

    def draw_cone_shader(self, glsl: str, texture: int, mode: int = 0) -> None:
        """The cone drawn by the kit's shader calling your ``reflect_eye`` and
        ``sphere_map_st`` (from ``glsl``), sampling ``texture`` on unit 1, under the
        current matrices. (``mode`` 1-4 write check values instead of colours.)"""
        GL = _gl()
        program = self._program(glsl, "SPHERE_MAP_GLSL")
        self.note("draw_cone_shader", texture=int(texture))
        previous = int(GL.glGetIntegerv(GL.GL_CURRENT_PROGRAM))
        GL.glUseProgram(program)
        GL.glUniform1i(_uniform(program, "sphere_map"), ENV_UNIT)
        GL.glUniform1i(_uniform(program, "mode"), int(mode))
        GL.glActiveTexture(GL.GL_TEXTURE0 + ENV_UNIT)
        GL.glBindTexture(GL.GL_TEXTURE_2D, int(texture))
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glMatrixMode(GL.GL_MODELVIEW)
        GL.glPushMatrix()
        GL.glMultMatrixd(np.ascontiguousarray(self.CONE_MODEL.T))
        self.mesh("cone").draw()
        GL.glPopMatrix()
        GL.glUseProgram(previous)

    def draw_cone_fixed_function(self) -> None:
        """The cone with no shader, in the fixed-function pipeline: its texture coordinates
        are whatever texgen makes of them, the texture the one bound on unit 0, replacing
        the colour (GL_REPLACE), with GL_NORMALIZE on."""
        GL = _gl()
        state = {
            "gen_s": bool(GL.glIsEnabled(GL.GL_TEXTURE_GEN_S)),
            "gen_t": bool(GL.glIsEnabled(GL.GL_TEXTURE_GEN_T)),
            "mode_s": int(np.asarray(GL.glGetTexGeniv(GL.GL_S, GL.GL_TEXTURE_GEN_MODE))
                          .reshape(-1)[0]),
            "mode_t": int(np.asarray(GL.glGetTexGeniv(GL.GL_T, GL.GL_TEXTURE_GEN_MODE))
                          .reshape(-1)[0]),
            "texture": int(GL.glGetIntegerv(GL.GL_TEXTURE_BINDING_2D)),
            "active_unit": int(GL.glGetIntegerv(GL.GL_ACTIVE_TEXTURE)) - GL.GL_TEXTURE0,
        }
        self.note("draw_cone_fixed_function", **state)
        previous = int(GL.glGetIntegerv(GL.GL_CURRENT_PROGRAM))
        GL.glUseProgram(0)
        GL.glDisable(GL.GL_LIGHTING)
        GL.glEnable(GL.GL_NORMALIZE)
        GL.glEnable(GL.GL_TEXTURE_2D)
        GL.glTexEnvi(GL.GL_TEXTURE_ENV, GL.GL_TEXTURE_ENV_MODE, GL.GL_REPLACE)
        GL.glMatrixMode(GL.GL_MODELVIEW)
        GL.glPushMatrix()
        GL.glMultMatrixd(np.ascontiguousarray(self.CONE_MODEL.T))
        mesh = self.mesh("cone")
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, mesh.vbo)
        GL.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, mesh.ebo)
        GL.glEnableClientState(GL.GL_VERTEX_ARRAY)
        GL.glVertexPointer(3, GL.GL_FLOAT, 32, GL.GLvoidp(0))
        GL.glEnableClientState(GL.GL_NORMAL_ARRAY)
        GL.glNormalPointer(GL.GL_FLOAT, 32, GL.GLvoidp(12))
        GL.glDrawElements(GL.GL_TRIANGLES, mesh.count, GL.GL_UNSIGNED_INT, None)
        GL.glDisableClientState(GL.GL_VERTEX_ARRAY)
        GL.glDisableClientState(GL.GL_NORMAL_ARRAY)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, 0)
        GL.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, 0)
        GL.glPopMatrix()
        GL.glDisable(GL.GL_TEXTURE_2D)
        GL.glDisable(GL.GL_NORMALIZE)
        GL.glUseProgram(previous)


# --------------------------------------------------------------------------- cube-map lab


class CubeMapLab(LabBase):
    """A chrome sphere on a pedestal among four coloured objects: the sphere drawn by the
    kit's shader through your face selection, sampling the cube map you capture."""

    name = "cubemap"
    EYE = (1.3, 2.0, 7.4)
    TARGET = (0.0, 0.1, 0.0)
    FOVY, NEAR, FAR = 38.0, 0.2, 60.0
    CENTER = (0.0, 0.0, 0.0)
    """The sphere's centre: where the six capture cameras sit."""
    BACKGROUND = (0.55, 0.7, 0.9)
    OBJECTS = (
        ("base", math3d.translate((0.0, -1.25, 0.0)), (1.0, 1.0, 1.0), "metal"),
        ("hand", math3d.translate((2.1, 0.1, 0.9)) @ math3d.rotate(30.0, (0, 1, 0)),
         (0.9, 0.12, 0.1), None),
        ("joint", math3d.translate((-1.9, 0.9, 1.3)), (0.15, 0.35, 0.95), None),
        ("lower_arm", math3d.translate((0.6, -1.25, -2.6)) @ math3d.rotate(20.0, (0, 1, 0)),
         (0.95, 0.75, 0.15), None),
        ("upper_arm", math3d.translate((-2.4, -1.25, -1.0)) @ math3d.rotate(-35.0, (0, 1, 0)),
         (0.2, 0.75, 0.3), None),
        ("backdrop", math3d.translate((0.0, 0.0, -9.0)), (0.85, 0.85, 0.85), "launch"),
    )

    def __init__(self, size: tuple[int, int], window: Any = None) -> None:
        super().__init__(size, window)
        self._programs: dict[str, int] = {}
        self._textures: dict[str, int] = {}
        for name in ("metal", "launch"):
            texture = int(_gl().glGenTextures(1))
            self.load_picture_texture(texture, name)
            self._textures[name] = texture

    def viewer_matrices(self) -> tuple[np.ndarray, np.ndarray]:
        return (math3d.perspective(self.FOVY, self.width / self.height, self.NEAR, self.FAR),
                math3d.look_at(self.EYE, self.TARGET, (0.0, 1.0, 0.0)))

    def set_viewer(self) -> None:
        """The viewer's projection and camera."""
        self.set_camera(*self.viewer_matrices())

    def draw_scene(self) -> None:
        """The pedestal, the four objects and the picture behind them, lit, under the
        current matrices. Never the sphere."""
        self._draw_parts([(mesh, model, color, self._textures.get(texture or ""))
                          for mesh, model, color, texture in self.OBJECTS],
                         light_world=(0.45, 0.55, 0.7))

    def _program(self, glsl: str) -> int:
        if not isinstance(glsl, str):
            raise LabSetupError(f"CUBE_MAP_GLSL must be a string of GLSL, got "
                                f"{type(glsl).__name__}")
        if glsl not in self._programs:
            self._programs[glsl] = compile_program("kit_cube.vert", "kit_cube.frag", glsl,
                                                   "CUBE_MAP_GLSL")
        return self._programs[glsl]

    def draw_sphere(self, glsl: str, cube_texture: int, mode: int = 0) -> None:
        """The chrome sphere at :attr:`CENTER`, drawn by the kit's shader: it reflects the eye
        ray in world space, asks your ``cube_face`` and ``cube_face_st`` (from ``glsl``)
        where that lands, and samples ``cube_texture`` (a GL_TEXTURE_CUBE_MAP, on unit 1)
        there. (``mode`` 1-2 write check values instead of colours.)"""
        GL = _gl()
        program = self._program(glsl)
        projection, modelview = current_matrices()
        self.note("draw_sphere", texture=int(cube_texture))
        eye = -modelview[:3, :3].T @ modelview[:3, 3]
        previous = int(GL.glGetIntegerv(GL.GL_CURRENT_PROGRAM))
        GL.glUseProgram(program)
        GL.glUniform1i(_uniform(program, "cube_map"), ENV_UNIT)
        GL.glUniform1i(_uniform(program, "mode"), int(mode))
        GL.glUniform3f(_uniform(program, "eye_world"), *(float(v) for v in eye))
        GL.glUniformMatrix4fv(_uniform(program, "view_projection"), 1, GL.GL_TRUE,
                              (projection @ modelview).astype(np.float32))
        GL.glActiveTexture(GL.GL_TEXTURE0 + ENV_UNIT)
        GL.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, int(cube_texture))
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glEnable(GL.GL_TEXTURE_CUBE_MAP_SEAMLESS)
        self.mesh("env_sphere").draw()
        GL.glUseProgram(previous)


def _announce(session: LabBase) -> None:
    global _session
    _session = session


def open_session(lab: str, size: tuple[int, int], window: Any = None) -> LabBase:
    """Make the session of ``lab`` in the current context (the harness does this before a
    student's file runs); :func:`lab20` and the others return it."""
    kinds = {"lab20": Lab20, "spheremap": SphereMapLab, "cubemap": CubeMapLab}
    session = kinds[lab](size, window)
    _announce(session)
    return session


def close_session() -> None:
    global _session
    _session = None


if __name__ == "__main__":  # pragma: no cover - a student ran the kit itself
    sys.exit("mirrorlab.labs.kit is used by a lab's starter.py; run 'mirrorlab lab run LAB'")
