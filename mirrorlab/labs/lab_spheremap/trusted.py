"""The sphere-map lab's trusted side: its session (the cone before the launch picture,
drawn by the student's GLSL or by texgen), its kit calls as the executor runs them, what
the checker observes after the frames (the check values and the value probe of the
student's GLSL) and the calls it leaves out. OpenGL is imported on first use."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from mirrorlab import math3d
from mirrorlab.labs.trusted import legacy
from mirrorlab.labs.trusted.calls import UNITS
from mirrorlab.labs.trusted.session import (
    ENV_UNIT,
    LabBase,
    LabSetupError,
    Mesh,
    kit_state,
    lazy_gl,
    modelview_times,
    uniform,
)
from mirrorlab.labs.trusted.state import GL_TEXTURE_2D
from mirrorlab.labs.trusted.variants import Variant

if TYPE_CHECKING:
    from mirrorlab.labs.trusted.call_executor import Executor
    from mirrorlab.labs.trusted.lab_run import LabRun


def left_out() -> dict[str, str]:
    """Calls of the allow-list (:data:`~mirrorlab.labs.trusted.calls.GL_SPECS`) this lab's
    handout does not need, with why."""
    from mirrorlab.labs.trusted import calls

    return {
        **{name: "the sphere-map lab captures nothing" for name in calls.COPIES},
        **{
            name: "the sphere-map lab gives no program with uniforms to set"
            for name in calls.UNIFORMS
        },
    }


def channels() -> tuple[str, ...]:
    """The ways of :data:`~mirrorlab.labs.trusted.calls.CHANNELS` from a file's numbers to
    the frame this lab's handout teaches: texgen's modes for s and t (the kit draws
    everything, and textures its cone itself)."""
    return ("texgen",)


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
        self.backdrop_texture = int(lazy_gl().glGenTextures(1))
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
        GL = lazy_gl()
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
        with kit_state(), modelview_times(self.cone_model):
            legacy.load_matrix_uniforms(program)
            self.mesh("cone").draw()
        GL.glUseProgram(previous)

    def draw_cone_fixed_function(self) -> None:
        """The cone with no shader, in the fixed-function pipeline: its texture coordinates
        whatever texgen makes of s and t on the variant's unit, textured there with the 2D
        texture bound on it (GL_REPLACE, the texture matrix the identity, no r or q
        generated, the current q 1); texturing off on every other unit the labs' calls can name, no
        lighting, normals normalised, the kit's raster state (:func:`kit_state`); all
        of it as the file left it again after."""
        GL = lazy_gl()
        FF = legacy.gl()
        previous = int(GL.glGetIntegerv(GL.GL_CURRENT_PROGRAM))
        active = int(GL.glGetIntegerv(GL.GL_ACTIVE_TEXTURE))
        GL.glUseProgram(0)
        normalize = bool(FF.glIsEnabled(GL.GL_NORMALIZE))
        FF.glEnable(GL.GL_NORMALIZE)
        saved: list[tuple[int, int, bool]] = []
        texgen = GL.GL_TEXTURE0 + self.texgen_unit
        for unit in sorted(UNITS):
            GL.glActiveTexture(unit)
            for cap in (
                GL.GL_TEXTURE_2D,
                GL.GL_TEXTURE_CUBE_MAP,
                *((GL.GL_TEXTURE_GEN_R, GL.GL_TEXTURE_GEN_Q) if unit == texgen else ()),
            ):
                saved.append((unit, cap, bool(FF.glIsEnabled(cap))))
                FF.glDisable(cap)
        GL.glActiveTexture(texgen)
        FF.glEnable(GL.GL_TEXTURE_2D)
        environment = int(
            np.asarray(FF.glGetTexEnviv(GL.GL_TEXTURE_ENV, GL.GL_TEXTURE_ENV_MODE)).reshape(-1)[0]
        )
        FF.glTexEnvi(GL.GL_TEXTURE_ENV, GL.GL_TEXTURE_ENV_MODE, GL.GL_REPLACE)
        texture_matrix = legacy.texture_matrix(self.texgen_unit)
        FF.glMatrixMode(GL.GL_TEXTURE)
        FF.glLoadIdentity()
        coordinates = legacy.current_texcoords(self.texgen_unit)
        FF.glMultiTexCoord4f(texgen, 0.0, 0.0, 0.0, 1.0)  # q is 1: s and t as texgen makes them
        mesh = self.mesh("cone")
        emulation = legacy.emulated()
        try:
            with kit_state(), modelview_times(self.cone_model):
                if emulation is not None:
                    emulation.draw_elements(mesh.vao, mesh.count)
                else:
                    self._draw_client_arrays(mesh)
        finally:
            GL.glActiveTexture(texgen)
            FF.glMatrixMode(GL.GL_TEXTURE)
            FF.glLoadMatrixd(np.ascontiguousarray(texture_matrix.T))
            FF.glMatrixMode(GL.GL_MODELVIEW)
            FF.glMultiTexCoord4f(texgen, *(float(c) for c in coordinates))
            FF.glTexEnvi(GL.GL_TEXTURE_ENV, GL.GL_TEXTURE_ENV_MODE, environment)
            for unit, cap, on in saved:
                GL.glActiveTexture(unit)
                (FF.glEnable if on else FF.glDisable)(cap)
            GL.glActiveTexture(active)
            (FF.glEnable if normalize else FF.glDisable)(GL.GL_NORMALIZE)
            GL.glUseProgram(previous)

    @staticmethod
    def _draw_client_arrays(mesh: Mesh) -> None:
        """The cone from client-state arrays (the compatibility profile's own pipeline)."""
        GL = lazy_gl()
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


SESSION = SphereMapLab


def kit_calls() -> dict[str, Any]:
    """The lab object's own calls, each ``handler(executor, args)``."""
    return {
        "draw_backdrop": draw_backdrop,
        "draw_cone_shader": draw_cone_shader,
        "draw_cone_fixed_function": draw_cone_fixed_function,
    }


def draw_backdrop(executor: Executor, args: list[Any]) -> None:
    bound = executor.record_draw("draw_backdrop", executor.lab.draw_backdrop)
    executor.after_kit_draw(bound)


def draw_cone_shader(executor: Executor, args: list[Any]) -> None:
    if len(args) != 2:
        raise LabSetupError("lab.draw_cone_shader(glsl, texture)")
    glsl = executor.take_glsl(args[0], "SPHERE_MAP_GLSL")
    texture = executor.owned_texture(args[1], "lab.draw_cone_shader", GL_TEXTURE_2D)
    executor.record_draw(
        "draw_cone_shader",
        lambda: executor.lab.draw_cone_shader(glsl, texture, 0, executor.limits.programs),
        texture=texture,
    )
    tracker = executor.tracker
    tracker.bindings[(1, GL_TEXTURE_2D)] = tracker.setting(texture)
    executor.after_kit_draw([])


def draw_cone_fixed_function(executor: Executor, args: list[Any]) -> None:
    GL = lazy_gl()
    session = executor.session
    unit = int(getattr(session, "texgen_unit", 0))
    previous = int(GL.glGetIntegerv(GL.GL_ACTIVE_TEXTURE))
    GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
    FF = legacy.gl()
    seen = {
        "unit": unit,
        "gen_s": bool(FF.glIsEnabled(GL.GL_TEXTURE_GEN_S)),
        "gen_t": bool(FF.glIsEnabled(GL.GL_TEXTURE_GEN_T)),
        "mode_s": int(np.asarray(FF.glGetTexGeniv(GL.GL_S, GL.GL_TEXTURE_GEN_MODE)).reshape(-1)[0]),
        "mode_t": int(np.asarray(FF.glGetTexGeniv(GL.GL_T, GL.GL_TEXTURE_GEN_MODE)).reshape(-1)[0]),
        "texture": int(GL.glGetIntegerv(GL.GL_TEXTURE_BINDING_2D)),
    }
    GL.glActiveTexture(previous)
    executor.record_draw(
        "draw_cone_fixed_function", executor.lab.draw_cone_fixed_function, seen=seen
    )
    executor.ok()


def observe(run: LabRun) -> None:
    """What the checker observes after the frames (into ``run.evidence``)."""
    session = run.session
    assert isinstance(session, SphereMapLab)
    tracker = run.executor.tracker
    run.evidence.state["backdrop_texture"] = session.backdrop_texture
    run.evidence.state["launch"] = next(
        (t.name for t in tracker.textures.values() if t.picture == "launch"), 0
    )
    # the GLSL the cone was drawn with, else the file's SPHERE_MAP_GLSL
    glsl = run.executor.glsl.get("SPHERE_MAP_GLSL") or run.declared.get("SPHERE_MAP_GLSL")
    if glsl is not None:
        run.probe_glsl("kit_sphere.vert", "kit_sphere.frag", glsl, "SPHERE_MAP_GLSL")
        # the cone's pixels (where the kit's u is written), for the frame's regions
        run.check_values(
            lambda mode: session.draw_cone_shader(glsl, session.backdrop_texture, mode, limit=64),
            {"u": 2},
            "reflect_eye",
        )
