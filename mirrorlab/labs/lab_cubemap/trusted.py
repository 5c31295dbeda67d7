"""The cube-map lab's trusted side: its session (the chrome sphere among coloured
objects, drawn by the student's GLSL from the cube map), its kit calls as the executor
runs them, what the checker observes after the frames (the cube map's faces, the check
values and the value probe of the student's GLSL) and the calls it leaves out. OpenGL is
imported on first use."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from mirrorlab import math3d
from mirrorlab.labs.lab_cubemap.variant import cube_center
from mirrorlab.labs.trusted import legacy
from mirrorlab.labs.trusted.session import (
    ENV_UNIT,
    LabBase,
    LabSetupError,
    current_matrices,
    kit_state,
    lazy_gl,
    read_cube_faces,
    uniform,
)
from mirrorlab.labs.trusted.state import GL_TEXTURE_CUBE_MAP
from mirrorlab.labs.trusted.variants import Variant

if TYPE_CHECKING:
    from mirrorlab.labs.trusted.call_executor import Executor
    from mirrorlab.labs.trusted.lab_run import LabRun


def left_out() -> dict[str, str]:
    """Calls of the allow-list (:data:`~mirrorlab.labs.trusted.calls.GL_SPECS`) this lab's
    handout does not need, with why."""
    from mirrorlab.labs.trusted import calls

    return {
        **{
            name: "the cube-map lab gives no program with uniforms to set"
            for name in calls.UNIFORMS
        },
        **{name: "the cube-map lab's shader makes the lookup; no texgen" for name in calls.TEXGEN},
    }


def channels() -> tuple[str, ...]:
    """The ways of :data:`~mirrorlab.labs.trusted.calls.CHANNELS` from a file's numbers to
    the frame this lab's handout teaches: the six copies of the capture."""
    return ("copies",)


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
            texture = int(lazy_gl().glGenTextures(1))
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
        GL = lazy_gl()
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
        with kit_state():
            self.mesh("env_sphere").draw()
        GL.glUseProgram(previous)


SESSION = CubeMapLab


def kit_calls() -> dict[str, Any]:
    """The lab object's own calls, each ``handler(executor, args)``."""
    return {"draw_scene": draw_scene, "draw_sphere": draw_sphere}


def draw_scene(executor: Executor, args: list[Any]) -> None:
    bound = executor.record_draw("draw_scene", executor.lab.draw_scene)
    executor.after_kit_draw(bound)


def draw_sphere(executor: Executor, args: list[Any]) -> None:
    if len(args) != 2:
        raise LabSetupError("lab.draw_sphere(glsl, cube_texture)")
    glsl = executor.take_glsl(args[0], "CUBE_MAP_GLSL")
    texture = executor.owned_texture(args[1], "lab.draw_sphere", GL_TEXTURE_CUBE_MAP)
    record = executor.tracker.textures.get(texture)
    extra: dict[str, Any] = {"texture": texture}
    if record is not None:
        extra["sampling"] = {str(k): v.plain() for k, v in record.params.items()}
        extra["mipmaps_fresh"] = record.mipmaps_fresh
        extra["mipmaps"] = record.mipmaps.plain() if record.mipmaps else None
    executor.record_draw(
        "draw_sphere",
        lambda: executor.lab.draw_sphere(glsl, texture, 0, executor.limits.programs),
        **extra,
    )
    tracker = executor.tracker
    tracker.bindings[(1, GL_TEXTURE_CUBE_MAP)] = tracker.setting(texture)
    executor.after_kit_draw([])


def observe(run: LabRun) -> None:
    """What the checker observes after the frames (into ``run.evidence``)."""
    GL = lazy_gl()
    session = run.session
    assert isinstance(session, CubeMapLab)
    evidence, tracker = run.evidence, run.executor.tracker
    draws = evidence.events("draw", who="draw_sphere", within="display")
    cube = (
        int(draws[-1]["texture"])
        if draws
        else next((t.name for t in tracker.textures.values() if t.target == GL_TEXTURE_CUBE_MAP), 0)
    )
    evidence.state["cube_texture"] = cube
    if cube and GL.glIsTexture(cube):
        faces = read_cube_faces(cube)
        if faces is not None:
            evidence.arrays["cube_faces"] = faces
    glsl = run.executor.glsl.get("CUBE_MAP_GLSL") or run.declared.get("CUBE_MAP_GLSL")
    if glsl is not None:
        run.probe_glsl("kit_cube.vert", "kit_cube.frag", glsl, "CUBE_MAP_GLSL")
        # the sphere's pixels (where the kit's r is written), for the frame's regions
        run.check_values(
            lambda mode: session.draw_sphere(glsl, cube, mode, limit=64), {"r": 2}, "cube_face"
        )
